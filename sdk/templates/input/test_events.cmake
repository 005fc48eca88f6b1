# facepuppet monitor prints the plugin's events as JSON lines; fails unless joint angles
# and the end of stream arrive. Called by ctest with FACEPUPPET and PLUGIN_DIR.
execute_process(
  COMMAND ${FACEPUPPET} monitor --plugin-dir ${PLUGIN_DIR} sine,duration=0.5,rate=100
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 30)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "facepuppet monitor failed (exit ${rc}): ${err}")
endif()
string(REGEX MATCHALL "joint_angles|angles" angles "${out}")
list(LENGTH angles n)
if(n LESS 20)
  message(FATAL_ERROR "expected about 50 joint-angle events, got ${n}:\n${out}")
endif()
if(NOT out MATCHES "end")
  message(FATAL_ERROR "no end-of-stream status:\n${out}")
endif()
message("input-sine delivered ${n} joint-angle events")
