# Checks that every ```cpp, ```cmake and ```yaml block of DOC is a verbatim excerpt of a file in
# CONSUMER_DIR, the plugin project that the consumer test builds and runs: so every snippet of the
# plugin guide is code that compiles (or a config that loads). Run as `cmake -P`.
# Variables: DOC, CONSUMER_DIR.

cmake_minimum_required(VERSION 3.25)

foreach(variable DOC CONSUMER_DIR)
  if(NOT DEFINED ${variable})
    message(FATAL_ERROR "check_docs.cmake: ${variable} is not set")
  endif()
endforeach()

file(GLOB sources "${CONSUMER_DIR}/*.cpp" "${CONSUMER_DIR}/*.hpp" "${CONSUMER_DIR}/*.yaml"
     "${CONSUMER_DIR}/CMakeLists.txt")
set(corpus "")
foreach(source IN LISTS sources)
  file(READ "${source}" text)
  string(APPEND corpus "${text}\n")
endforeach()

file(READ "${DOC}" doc)
set(checked 0)
set(failures "")
set(rest "${doc}")
while(TRUE)
  string(REGEX MATCH "```(cpp|cmake|yaml)\n" fence "${rest}")
  if(NOT fence)
    break()
  endif()
  string(FIND "${rest}" "${fence}" start)
  string(LENGTH "${fence}" fence_length)
  math(EXPR start "${start} + ${fence_length}")
  string(SUBSTRING "${rest}" ${start} -1 rest)
  string(FIND "${rest}" "```" end)
  if(end LESS 0)
    message(FATAL_ERROR "${DOC}: a ${fence} block is not closed")
  endif()
  string(SUBSTRING "${rest}" 0 ${end} block)
  string(SUBSTRING "${rest}" ${end} -1 rest)
  string(SUBSTRING "${rest}" 3 -1 rest)
  math(EXPR checked "${checked} + 1")
  string(FIND "${corpus}" "${block}" found)
  if(found LESS 0)
    string(STRIP "${fence}" language)
    string(APPEND failures
           "\n--- block ${checked} (${language}) is in no file of ${CONSUMER_DIR}:\n"
           "${block}")
  endif()
endwhile()

if(checked EQUAL 0)
  message(FATAL_ERROR "${DOC} has no code blocks to check")
endif()
if(failures)
  message(FATAL_ERROR "${DOC}: snippets that are not verbatim excerpts:${failures}")
endif()
message(STATUS "${checked} snippets of ${DOC} are verbatim excerpts of ${CONSUMER_DIR}")
