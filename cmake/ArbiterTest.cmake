# arbiter_add_test(NAME PATH... [ONE_TEST] [PLUGIN_PATH DIR...])
#
# Registers CTest tests that run `arbiter test` over scenario test files or directories (every
# *.test.yaml, *.test.yml and *.test.json in them); relative paths are taken from the current
# source directory. Each scenario is a test of its own, NAME/SCENARIO (SCENARIO: the file's path
# relative to the directory given, without .test.yaml), so that CTest reports them one by one;
# the directories are read again when a scenario is added or removed. A path that does not exist
# yet at configure time (a directory a fixture fills), or every path with ONE_TEST, is run by one
# test, NAME. A test fails when its scenario fails or its file is invalid, with each failed
# expectation at its file:line:col in the test's output. The plugins built with
# arbiter_add_plugin() in this project are found without flags; PLUGIN_PATH adds directories.
# The tests are labelled `arbiter`.
function(arbiter_add_test name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "ONE_TEST" "" "PLUGIN_PATH")
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
  get_property(plugins GLOBAL PROPERTY ARBITER_PLUGIN_TARGETS)
  set(directories)
  foreach(plugin IN LISTS plugins)
    list(APPEND directories "$<TARGET_FILE_DIR:${plugin}>")
  endforeach()
  list(APPEND directories ${ARG_PLUGIN_PATH})
  list(REMOVE_DUPLICATES directories)
  set(options)
  foreach(directory IN LISTS directories)
    list(APPEND options "--plugin-path=${directory}")
  endforeach()
  # The paths come first: a repeatable option would take the words after it as more values.
  set(together)
  foreach(path IN LISTS paths)
    get_filename_component(path "${path}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    set(files)
    if(ARG_ONE_TEST OR NOT EXISTS "${path}")
      list(APPEND together "${path}")
      continue()
    elseif(IS_DIRECTORY "${path}")
      file(GLOB_RECURSE files CONFIGURE_DEPENDS "${path}/*.test.yaml" "${path}/*.test.yml"
           "${path}/*.test.json")
      list(SORT files)
      set(base "${path}")
      if(NOT files)
        message(FATAL_ERROR "arbiter_add_test(${name}): no test files (*.test.yaml, *.test.yml, "
                            "*.test.json) in ${path}")
      endif()
    else()
      set(files "${path}")
      get_filename_component(base "${path}" DIRECTORY)
    endif()
    foreach(file IN LISTS files)
      file(RELATIVE_PATH scenario "${base}" "${file}")
      string(REGEX REPLACE "\\.test\\.(yaml|yml|json)$" "" scenario "${scenario}")
      add_test(NAME "${name}/${scenario}" COMMAND "${executable}" test "${file}" ${options})
      set_tests_properties("${name}/${scenario}" PROPERTIES LABELS arbiter)
    endforeach()
  endforeach()
  if(together)
    add_test(NAME "${name}" COMMAND "${executable}" test ${together} ${options})
    set_tests_properties("${name}" PROPERTIES LABELS arbiter)
  endif()
endfunction()
