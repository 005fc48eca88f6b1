# Add every direct sub-folder of DIR that has a CMakeLists.txt, in name order, so that new
# components (a plugin, a core module, a test folder) need no edit of a shared list.
function(fp_add_subdirs dir)
  if(EXISTS ${CMAKE_SOURCE_DIR}/${dir}/CMakeLists.txt)
    add_subdirectory(${dir})
    return()
  endif()
  file(GLOB children LIST_DIRECTORIES true ${CMAKE_SOURCE_DIR}/${dir}/*)
  list(SORT children)
  foreach(child ${children})
    if(IS_DIRECTORY ${child} AND EXISTS ${child}/CMakeLists.txt)
      add_subdirectory(${child})
    endif()
  endforeach()
endfunction()

# fp_add_plugin(NAME SOURCES...): a MODULE library named NAME.so in build/lib/facepuppet,
# built against the public plugin header only, installed with the project.
function(fp_add_plugin name)
  add_library(${name} MODULE ${ARGN})
  set_target_properties(${name} PROPERTIES PREFIX "" LIBRARY_OUTPUT_DIRECTORY ${FP_PLUGIN_OUTPUT_DIR}
                        C_VISIBILITY_PRESET hidden)
  target_include_directories(${name} PRIVATE ${CMAKE_SOURCE_DIR}/core/include)
  install(TARGETS ${name} LIBRARY DESTINATION ${FP_PLUGIN_SUBDIR})
endfunction()

# Sanitizer builds (FP_SANITIZE=ON, set by the sanitizers preset, build-asan/): every test
# gets the ASan/LSan/UBSan options below (LSan suppressions for Mesa, X and LLVM in
# tests/lsan.supp; verify_asan_link_order=0 so that umockdev's and the tests' LD_PRELOAD
# libraries may come before ASan; UBSan findings fail the test) and FP_TEST_TIMEOUT_SCALE
# times its timeout.
set(FP_TEST_TIMEOUT_SCALE 1)
set(FP_SANITIZER_ENV "")
# Tests that draw with Mesa's llvmpipe (viewer, png-seq export): no leak check in sanitizer
# builds. Mesa is built without frame pointers, so the allocations it keeps for the process's
# life unwind to no module and tests/lsan.supp cannot match them; every other test keeps
# LeakSanitizer on. Pass as fp_test_env(... ENV ${FP_GL_ASAN_ENV}).
set(FP_GL_ASAN_ENV "")
if(FP_SANITIZE)
  set(FP_GL_ASAN_ENV "ASAN_OPTIONS=verify_asan_link_order=0:detect_leaks=0")
  set(FP_TEST_TIMEOUT_SCALE 3)
  set(FP_SANITIZER_ENV
      "ASAN_OPTIONS=verify_asan_link_order=0:detect_leaks=1"
      "LSAN_OPTIONS=suppressions=${CMAKE_SOURCE_DIR}/tests/lsan.supp:print_suppressions=0"
      "UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1"
      "FP_TEST_TIME_SCALE=${FP_TEST_TIMEOUT_SCALE}") # a test's own wall-clock limits (test_onehand_session)
endif()

# fp_test_env(NAME [TIMEOUT seconds] [ENV VAR=value...]): the one place a test's timeout
# (default 300 s, times FP_TEST_TIMEOUT_SCALE) and environment are set: FP_SHARED_DATA,
# FP_BUILD_DIR, the sanitizer options of a sanitizer build, then ENV. For tests made with
# add_test (shell scripts, wrappers); fp_add_test calls it.
function(fp_test_env name)
  cmake_parse_arguments(E "" "TIMEOUT" "ENV" ${ARGN})
  if(NOT E_TIMEOUT)
    set(E_TIMEOUT 300)
  endif()
  math(EXPR t "${E_TIMEOUT} * ${FP_TEST_TIMEOUT_SCALE}")
  set_tests_properties(${name} PROPERTIES TIMEOUT ${t} ENVIRONMENT
    "FP_SHARED_DATA=${FP_SHARED_DATA};FP_BUILD_DIR=${CMAKE_BINARY_DIR};${FP_SANITIZER_ENV};${E_ENV}")
endfunction()

# fp_add_test(NAME SOURCES... [LIBS libs...]): a cmocka test run by ctest from the source tree
# root, so that ../shared/data resolves as everywhere else.
function(fp_add_test name)
  cmake_parse_arguments(T "" "TIMEOUT" "LIBS" ${ARGN})
  add_executable(${name} ${T_UNPARSED_ARGUMENTS})
  pkg_check_modules(CMOCKA REQUIRED IMPORTED_TARGET cmocka)
  target_link_libraries(${name} PRIVATE PkgConfig::CMOCKA ${T_LIBS} m)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  add_test(NAME ${name} COMMAND ${name} WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  fp_test_env(${name} TIMEOUT ${T_TIMEOUT})
endfunction()

# fp_add_fuzz(NAME SOURCES... [LIBS libs...] [CORPUS dirs...]): a libFuzzer target (clang,
# ASan + UBSan), built only in the fuzz build (cmake --preset fuzz, build-fuzz/, FP_FUZZ=ON).
# CORPUS: seed folders, relative to the source root or absolute (e.g. tests/fuzz/corpus/NAME,
# ../shared/data/...); they are only read. New inputs go to build-fuzz/fuzz/corpus/NAME,
# crashes to build-fuzz/fuzz/artifacts/. Also a ctest `fuzz_NAME` (label fuzz) that runs the
# target for FP_FUZZ_SECONDS (default 20) and fails on any crash, leak, timeout or OOM.
# tools/fuzz-run reads build-fuzz/fuzz/NAME.corpus (one seed folder a line) for long runs.
function(fp_add_fuzz name)
  if(NOT FP_FUZZ)
    return()
  endif()
  cmake_parse_arguments(F "" "" "LIBS;CORPUS" ${ARGN})
  add_executable(${name} ${F_UNPARSED_ARGUMENTS})
  target_compile_options(${name} PRIVATE -fsanitize=fuzzer)
  target_link_options(${name} PRIVATE -fsanitize=fuzzer)
  target_link_libraries(${name} PRIVATE ${F_LIBS})
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/fuzz)
  set(dirs "")
  foreach(d ${F_CORPUS})
    if(NOT IS_ABSOLUTE ${d})
      set(d ${CMAKE_SOURCE_DIR}/${d})
    endif()
    string(APPEND dirs "${d}\n")
  endforeach()
  file(WRITE ${CMAKE_BINARY_DIR}/fuzz/${name}.corpus "${dirs}")
  if(NOT TARGET fuzz)
    add_custom_target(fuzz)
  endif()
  add_dependencies(fuzz ${name})
  if(NOT FP_FUZZ_SECONDS)
    set(FP_FUZZ_SECONDS 20)
  endif()
  add_test(NAME fuzz_${name}
           COMMAND ${CMAKE_SOURCE_DIR}/tools/fuzz-run --no-build ${FP_FUZZ_SECONDS} ${name}
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(fuzz_${name} PROPERTIES LABELS fuzz
    TIMEOUT 600 ENVIRONMENT "FP_FUZZ_BUILD_DIR=${CMAKE_BINARY_DIR}")
endfunction()
