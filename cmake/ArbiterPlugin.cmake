# arbiter_add_plugin(NAME SOURCES src... [LINK_LIBRARIES lib...])
#
# Builds an Arbiter plugin: a MODULE library named arbiter_NAME.so that `plugins: [NAME]` in a
# config loads from the plugin path (--plugin-path DIR, ARBITER_PLUGIN_PATH, or the directory
# ARBITER_PLUGIN_OUTPUT_DIRECTORY when set). The sources define the entry points with
# ARBITER_PLUGIN(registry) { ... } from <arbiter/plugin.hpp>.
function(arbiter_add_plugin name)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "" "SOURCES;LINK_LIBRARIES")
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "arbiter_add_plugin(${name}): no SOURCES given")
  endif()
  add_library(${name} MODULE ${ARG_SOURCES})
  # arbiter_add_test() runs scenarios with every plugin the project builds on the plugin path.
  set_property(GLOBAL APPEND PROPERTY ARBITER_PLUGIN_TARGETS ${name})
  target_link_libraries(${name} PRIVATE arbiter::core ${ARG_LINK_LIBRARIES})
  # The engine's headers need C++17, whatever the plugin project's default.
  target_compile_features(${name} PRIVATE cxx_std_17)
  set_target_properties(${name} PROPERTIES
    PREFIX ""
    OUTPUT_NAME "arbiter_${name}"
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON)
  if(ARBITER_PLUGIN_OUTPUT_DIRECTORY)
    set_target_properties(${name} PROPERTIES
      LIBRARY_OUTPUT_DIRECTORY "${ARBITER_PLUGIN_OUTPUT_DIRECTORY}")
  endif()
endfunction()
