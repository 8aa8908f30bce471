# arbiter_add_test(NAME PATH... [PLUGIN_PATH DIR...])
#
# Registers a CTest test, NAME, that runs `arbiter test` over scenario test files or directories
# (every *.test.yaml, *.test.yml and *.test.json in them); relative paths are taken from the
# current source directory. The test fails when a scenario fails or a test file is invalid, with
# each failed expectation at its file:line:col in the test's output. The plugins built with
# arbiter_add_plugin() in this project are found without flags; PLUGIN_PATH adds directories.
# The test is labelled `arbiter`.
function(arbiter_add_test name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "" "PLUGIN_PATH")
  set(paths ${ARG_UNPARSED_ARGUMENTS})
  if(NOT paths)
    message(FATAL_ERROR "arbiter_add_test(${name}): no test files or directories given")
  endif()
  if(TARGET arbiter)
    set(executable "$<TARGET_FILE:arbiter>")
  elseif(ARBITER_EXECUTABLE)
    set(executable "${ARBITER_EXECUTABLE}")
  else()
    message(FATAL_ERROR "arbiter_add_test(${name}): no arbiter executable (find_package(arbiter) "
                        "sets ARBITER_EXECUTABLE)")
  endif()
  # The paths first: a repeatable option would take the words after it as more values.
  set(arguments)
  foreach(path IN LISTS paths)
    get_filename_component(path "${path}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    list(APPEND arguments "${path}")
  endforeach()
  get_property(plugins GLOBAL PROPERTY ARBITER_PLUGIN_TARGETS)
  set(directories)
  foreach(plugin IN LISTS plugins)
    list(APPEND directories "$<TARGET_FILE_DIR:${plugin}>")
  endforeach()
  list(APPEND directories ${ARG_PLUGIN_PATH})
  list(REMOVE_DUPLICATES directories)
  foreach(directory IN LISTS directories)
    list(APPEND arguments "--plugin-path=${directory}")
  endforeach()
  add_test(NAME "${name}" COMMAND "${executable}" test ${arguments})
  set_tests_properties("${name}" PROPERTIES LABELS arbiter)
endfunction()
