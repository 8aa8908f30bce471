# cmake -DMODULE=cmake/ArbiterTest.cmake -DWORK_DIR=DIR -P add_test_check.cmake
#
# A project with three scenarios in a directory (one in a subdirectory, beside a file that is not
# a scenario) and a directory that does not exist yet: arbiter_add_test() registers one test per
# scenario, named after it, and one test for the missing directory.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/tests/more")
foreach(file tests/a.test.yaml tests/b.test.json tests/more/c.test.yml tests/README.md)
  file(WRITE "${WORK_DIR}/${file}" "")
endforeach()
file(WRITE "${WORK_DIR}/CMakeLists.txt" "cmake_minimum_required(VERSION 3.16)
project(scenarios NONE)
include(\"${MODULE}\")
set(ARBITER_EXECUTABLE /bin/true)
enable_testing()
arbiter_add_test(demo tests)
arbiter_add_test(later made_by_a_fixture)
")
execute_process(COMMAND "${CMAKE_COMMAND}" -S "${WORK_DIR}" -B "${WORK_DIR}/build"
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "configuring the project failed:\n${out}")
endif()
get_filename_component(cmake_bin "${CMAKE_COMMAND}" DIRECTORY)
execute_process(COMMAND "${cmake_bin}/ctest" -N WORKING_DIRECTORY "${WORK_DIR}/build"
                OUTPUT_VARIABLE listed)
message("${listed}")
foreach(test "demo/a" "demo/b" "demo/more/c" "later")
  if(NOT listed MATCHES "Test +#[0-9]+: ${test}\n")
    message(FATAL_ERROR "no test '${test}' registered")
  endif()
endforeach()
if(NOT listed MATCHES "Total Tests: 4\n")
  message(FATAL_ERROR "expected 4 tests")
endif()
