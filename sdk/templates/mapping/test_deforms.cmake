# Runs facepuppet with this plugin on a real face and a real recording; fails unless some
# vertices moved. Called by ctest with FACEPUPPET, PLUGIN_DIR, DATA, WORK.
execute_process(
  COMMAND ${FACEPUPPET} run --plugin-dir ${PLUGIN_DIR} --mapping grab,gain=1.5
          --mesh ${DATA}/faces/ict-facekit/generic_neutral_mesh.obj
          --input replay:${DATA}/hands/leap-motion/three-claps_joints_mm.csv
          --out ${WORK}/grabbed.obj
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "facepuppet run failed (exit ${rc})")
endif()
string(REGEX MATCH "vertices moved ([0-9]+) of" m "${out}${err}")
if(NOT CMAKE_MATCH_1 OR CMAKE_MATCH_1 EQUAL 0)
  message(FATAL_ERROR "the plugin loaded but moved no vertex")
endif()
message("map-grab moved ${CMAKE_MATCH_1} vertices")
