# The plugin SDK end to end, run by CTest as `cmake -P`:
#   1. installs Arbiter's build tree (BUILD_DIR) to a fresh prefix under WORK_DIR;
#   2. configures and builds this folder, the out-of-tree plugin project, against that prefix
#      with find_package(arbiter), nothing else; the plugin needs the core library, not the
#      tools one, and the package exports both targets;
#   3. runs the project's config with the *installed* CLI, finding the plugin through
#      --plugin-path and through ARBITER_PLUGIN_PATH, and checks what it reports;
#   4. runs the project's scenario tests through its CTest (arbiter_add_test);
#   5. checks that the installed CLI finds the installed soccer plugin with no flags, and that
#      it looks for plugins in the prefix, not in the build tree.
# Variables: BUILD_DIR, SOURCE_DIR (Arbiter's), WORK_DIR, CXX_COMPILER.

cmake_minimum_required(VERSION 3.25)

foreach(variable BUILD_DIR SOURCE_DIR WORK_DIR CXX_COMPILER)
  if(NOT DEFINED ${variable})
    message(FATAL_ERROR "consumer_test.cmake: ${variable} is not set")
  endif()
endforeach()

set(prefix "${WORK_DIR}/prefix")
set(consumer_build "${WORK_DIR}/build")
set(consumer_source "${SOURCE_DIR}/tests/consumer")
set(arbiter "${prefix}/bin/arbiter")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

include("${CMAKE_CURRENT_LIST_DIR}/../support/run_checked.cmake")

message(STATUS "installing ${BUILD_DIR} to ${prefix}")
run_checked(output 0 "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")

find_program(NINJA_PROGRAM ninja)
set(generator)
if(NINJA_PROGRAM)
  set(generator -G Ninja)
endif()
message(STATUS "building ${consumer_source} against ${prefix}")
run_checked(output 0 "${CMAKE_COMMAND}" -S "${consumer_source}" -B "${consumer_build}"
            ${generator} -DCMAKE_BUILD_TYPE=Debug "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}"
            "-DCMAKE_CXX_FLAGS=-Wall -Wextra -Wpedantic -Werror" "-DCMAKE_PREFIX_PATH=${prefix}")
run_checked(output 0 "${CMAKE_COMMAND}" --build "${consumer_build}" -j2)
if(NOT EXISTS "${consumer_build}/arbiter_patrol.so")
  message(FATAL_ERROR "the consumer build made no ${consumer_build}/arbiter_patrol.so")
endif()
find_program(OBJDUMP objdump REQUIRED)
run_checked(needed 0 "${OBJDUMP}" -p "${consumer_build}/arbiter_patrol.so")
expect_in("${needed}" "the libraries arbiter_patrol.so needs" "NEEDED +libarbiter\\.so\\.0\n")
if(needed MATCHES "libarbiter-tools")
  message(FATAL_ERROR "arbiter_patrol.so needs the tools library:\n${needed}")
endif()
file(GLOB_RECURSE targets "${prefix}/*/arbiterTargets.cmake")
file(READ "${targets}" targets_text)
expect_in("${targets_text}" "the installed package's targets"
  "add_library\\(arbiter::core SHARED IMPORTED\\)"
  "add_library\\(arbiter::tools SHARED IMPORTED\\)")

# The project's scenario tests, registered with arbiter_add_test(), pass in its own CTest.
message(STATUS "running the consumer's scenario tests with ctest")
get_filename_component(cmake_bin "${CMAKE_COMMAND}" DIRECTORY)
run_checked(output 0 "${CMAKE_COMMAND}" -E env --unset=ARBITER_PLUGIN_PATH
            "${cmake_bin}/ctest" --test-dir "${consumer_build}" --verbose)
expect_in("${output}" "ctest in the consumer project"
  "patrol_scenarios/patrol[ .]*Passed"
  "PASS [^\n]*patrol.test.yaml \\(6 expectations, 30 steps\\)")

# The plugin's classes run: the robot drives to the gate, then the lookout's countdown plans
# itself for three rounds; the beacon (the plugin's own value type) goes into the trace.
message(STATUS "running patrol.yaml with the installed arbiter and --plugin-path")
set(trace "${WORK_DIR}/patrol.jsonl")
run_checked(output 0 "${CMAKE_COMMAND}" -E env --unset=ARBITER_PLUGIN_PATH
            "${arbiter}" --plugin-path "${consumer_build}" run "${consumer_source}/patrol.yaml"
            --steps 40 --trace "${trace}")
expect_in("${output}" "arbiter run patrol.yaml"
  "running patrol: 2 layers, 2 behaviours, 1 state machines"
  "step    1  control/go_to_gate activated"
  "step    1  go_to_gate: setting off"
  "step    1  base: beacon on"
  "step   18  control/go_to_gate deactivated \\(requests 0\\)"
  "step   18  control/lookout activated"
  "step   18  go_to_gate: arrived\nstep   18  watch: countdown {rounds: 3} \\(cycle 1; queued: done\\)"
  "step   18  base: beacon off"
  "step   20  watch: countdown {rounds: 3} ended \\(proceeded\\)"
  "step   20  watch: countdown {steps: 2, rounds: 2} \\(cycle 3; queued: done\\)"
  "step   22  watch: countdown {steps: 2, rounds: 1} \\(cycle 5; queued: done\\)"
  "step   24  watch: done \\(cycle 7; queued: nothing\\)"
  "step   25  watch: done ended \\(proceeded, queue empty\\)\nstep   25  watch: finished"
  "State machine watch: finished after 8 cycles"
  "go_to_gate: arrived \\(1 time\\)"
  "control/go_to_gate +17  \\(final activation 0\\)")
file(READ "${trace}" trace_text)
expect_in("${trace_text}" "the trace of patrol.yaml"
  "\"beacon\": {\"value\": {\"on\": true, \"hz\": 2}, \"written\": true}"
  "\"position\": {\"value\": \\[0\\.9[0-9]+, 0\\.4[0-9]+\\], \"written\": true}")

message(STATUS "validating patrol.yaml with ARBITER_PLUGIN_PATH")
run_checked(output 0 "${CMAKE_COMMAND}" -E env
            "ARBITER_PLUGIN_PATH=${WORK_DIR}/nowhere:${consumer_build}"
            "${arbiter}" validate "${consumer_source}/patrol.yaml")
expect_in("${output}" "arbiter validate with ARBITER_PLUGIN_PATH" "patrol.yaml: ok")

message(STATUS "validating the soccer demo with the installed arbiter and no flags")
run_checked(output 0 "${CMAKE_COMMAND}" -E env --unset=ARBITER_PLUGIN_PATH
            "${arbiter}" validate "${SOURCE_DIR}/configs/soccer/walk_and_kick.yaml")
expect_in("${output}" "arbiter validate walk_and_kick.yaml" "walk_and_kick.yaml: ok")

# Without --plugin-path the patrol plugin is not found, and the installed arbiter says that it
# looked in the prefix (so the soccer plugin above came from there, not from the build tree).
run_checked(output 1 "${CMAKE_COMMAND}" -E env --unset=ARBITER_PLUGIN_PATH
            "${arbiter}" validate "${consumer_source}/patrol.yaml")
file(REAL_PATH "${prefix}" real_prefix)
expect_in("${output}" "arbiter validate patrol.yaml without --plugin-path"
  "patrol.yaml:7:11: error\\[plugin-not-found\\]: plugin 'patrol' not found: no arbiter_patrol.so on the plugin path"
  "patrol.yaml:7:11: note: looked in ${real_prefix}/lib[^\n]*/arbiter/plugins\n")
file(REAL_PATH "${BUILD_DIR}/plugins" build_plugins)
string(FIND "${output}" "looked in ${build_plugins}\n" found)
if(found GREATER_EQUAL 0)
  message(FATAL_ERROR "the installed arbiter looked in the build tree:\n${output}")
endif()
