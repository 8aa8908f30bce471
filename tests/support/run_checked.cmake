# Helpers of the tests run by CTest as `cmake -P` scripts that build and run installed things.
# The including script sets WORK_DIR, where the commands run.

# Runs a command in WORK_DIR; fails the test, with everything it printed, unless it exits with
# `expected`. The output (stdout and stderr together) is left in `out_var`.
function(run_checked out_var expected)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORK_DIR}" RESULT_VARIABLE result
                  OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT "${result}" STREQUAL "${expected}")
    string(REPLACE ";" " " command "${ARGN}")
    message(FATAL_ERROR "`${command}` exited with ${result}, not ${expected}:\n${output}")
  endif()
  set(${out_var} "${output}" PARENT_SCOPE)
endfunction()

# Fails the test unless `output` matches every pattern after `description`.
function(expect_in output description)
  foreach(pattern IN LISTS ARGN)
    if(NOT output MATCHES "${pattern}")
      message(FATAL_ERROR "${description}: expected to match '${pattern}' in:\n${output}")
    endif()
  endforeach()
endfunction()
