# The project `arbiter new plugin` writes builds against the installed SDK as written, warning
# free, and its scenario test passes in its CTest; its config runs and its classes are listed.
# Run by CTest as `cmake -P`, after the fixture that installs the build tree to PREFIX. CMake is
# given no CMAKE_PREFIX_PATH: it finds the package from `arbiter` on the PATH, as the starter's
# README and docs/tutorial.md say it does.
# Variables: PREFIX, WORK_DIR, CXX_COMPILER.
cmake_minimum_required(VERSION 3.25)

foreach(variable PREFIX WORK_DIR CXX_COMPILER)
  if(NOT DEFINED ${variable})
    message(FATAL_ERROR "new_plugin_build.cmake: ${variable} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(ENV{PATH} "${PREFIX}/bin:$ENV{PATH}")
unset(ENV{CMAKE_PREFIX_PATH})
unset(ENV{ARBITER_PLUGIN_PATH})
get_filename_component(cmake_bin "${CMAKE_COMMAND}" DIRECTORY)

include("${CMAKE_CURRENT_LIST_DIR}/../support/run_checked.cmake")

# A name the C library declares (random(), in <stdlib.h>): the project's namespace must not clash
# with it.
run_checked(output 0 "${PREFIX}/bin/arbiter" new plugin random)
run_checked(output 0 "${CMAKE_COMMAND}" -S random -B random/build -DCMAKE_BUILD_TYPE=Debug
            "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
            "-DCMAKE_CXX_FLAGS=-Wall -Wextra -Wpedantic -Werror")
file(REAL_PATH "${PREFIX}" real_prefix)
run_checked(output 0 "${CMAKE_COMMAND}" --build random/build -j2)
if(NOT EXISTS "${WORK_DIR}/random/build/arbiter_random.so")
  message(FATAL_ERROR "the starter project built no arbiter_random.so:\n${output}")
endif()
file(READ "${WORK_DIR}/random/build/CMakeCache.txt" cache)
string(REGEX MATCH "arbiter_DIR:PATH=[^\n]*" found "${cache}")
expect_in("${found}" "the SDK the starter project found" "^arbiter_DIR:PATH=${real_prefix}/")

run_checked(output 0 "${cmake_bin}/ctest" --test-dir random/build --output-on-failure)
expect_in("${output}" "ctest in the starter project" "random_scenarios/random[ .]*Passed"
          "100% tests passed, 0 tests failed out of 1")
run_checked(output 0 "${PREFIX}/bin/arbiter" test random/tests --plugin-path random/build)
expect_in("${output}" "arbiter test in the starter project"
          "PASS random/tests/random.test.yaml \\([0-9]+ expectations, 30 steps\\)")

run_checked(output 0 "${PREFIX}/bin/arbiter" --plugin-path random/build run random/random.yaml
            --steps 50)
expect_in("${output}" "arbiter run random.yaml"
  "running random: 2 layers, 2 behaviours, 1 state machines"
  "step    1  route: out \\(cycle 1; queued: back\\)"
  "State machine route: finished")
run_checked(output 0 "${PREFIX}/bin/arbiter" --plugin-path random/build plugins --load random)
expect_in("${output}" "arbiter plugins --load random" "random\\.Stop" "random\\.Drive")
message(STATUS "the starter project built against ${PREFIX} and its test passed")
