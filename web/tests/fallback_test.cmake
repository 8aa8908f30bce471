# The build of the web app when the npm registry is out of reach (web/bundle.cmake), as CTest runs
# it:
#   cmake -DSOURCE_DIR=web -DWORK_DIR=DIR -DNPM=npm -DESBUILD=esbuild
#         -DMISSING_PAGE=cli/server/web_missing.html -P web/tests/fallback_test.cmake
# npm ci runs in an empty DIR against a registry at a closed port with an empty cache: the script
# must warn, succeed, and write the page that says why, and leave no stamp so that the next build
# tries again.
cmake_minimum_required(VERSION 3.25)
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/cache")
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E env "npm_config_registry=http://127.0.0.1:9/"
          "npm_config_cache=${WORK_DIR}/cache" npm_config_fetch_retries=0 npm_config_offline=false
          "${CMAKE_COMMAND}" "-DSOURCE_DIR=${SOURCE_DIR}" "-DWORK_DIR=${WORK_DIR}/web"
          "-DNPM=${NPM}" "-DESBUILD=${ESBUILD}" -DLEFT_OUT= "-DMISSING_PAGE=${MISSING_PAGE}"
          "-DOUTPUT=${WORK_DIR}/web_assets.cpp" -P "${SOURCE_DIR}/bundle.cmake"
  RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE output)
message("${output}")
set(failures "")
if(NOT status EQUAL 0)
  list(APPEND failures "bundle.cmake failed (${status}): the build would fail")
endif()
# CMake wraps a warning's lines.
string(REGEX REPLACE "[ \n]+" " " flat "${output}")
if(NOT flat MATCHES "web app left out: `npm ci` in [^ ]* failed \\(npm (error|ERR!)")
  list(APPEND failures "no warning that says npm ci failed")
endif()
if(NOT EXISTS "${WORK_DIR}/web_assets.cpp")
  list(APPEND failures "no web_assets.cpp written")
else()
  file(READ "${WORK_DIR}/web_assets.cpp" source)
  if(NOT source MATCHES "kLeftOut = \"`npm ci` in [^\n]* failed" OR NOT source MATCHES "kAssetCount = 1;")
    list(APPEND failures "web_assets.cpp does not hold the missing page alone, with the reason")
  endif()
endif()
file(READ "${WORK_DIR}/web/missing/index.html" page)
if(NOT page MATCHES "was built without its web page: `npm ci` in [^\n]* failed")
  list(APPEND failures "the page does not say why")
endif()
if(EXISTS "${WORK_DIR}/web/bundle.stamp")
  list(APPEND failures "bundle.stamp written: the next build would not try again")
endif()
if(failures)
  string(REPLACE ";" "\n  " failures "${failures}")
  message(FATAL_ERROR "failed:\n  ${failures}")
endif()
