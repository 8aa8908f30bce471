#!/usr/bin/env bash
# The browser tests of the web app (browser_test.mjs; TEST.mjs another, studio_test.mjs), as CTest
# runs them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR [TEST.mjs]
#   run.sh ARBITER SOURCE_DIR WORK_DIR bench/SCRIPT.mjs [ARGS...]   (a benchmark of web/bench/, run once)
# WORK_DIR (BUILD/web) holds the node_modules that the build installed from web/package-lock.json
# (web/bundle.cmake); npm_ci_into installs it there if the build did not (tests/support/npm_ci.sh).
# ARBITER_SCREENSHOT=docs/live_view.png also saves the README's screenshot of the soccer demo;
# ARBITER_FRAME_BUDGET_MS=16 checks the live page's frame-time target (docs/performance.md).
set -euo pipefail
arbiter=$1
source=$2
work=$3
. "$source/tests/support/npm_ci.sh"
npm_ci_into "$source/web" "$work" node_modules/playwright-core
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
export CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
if [[ ${4:-} == bench/* ]]; then
  exec node "$source/web/$4" "${@:5}"
fi
exec node --test "$source/web/tests/${4:-browser_test.mjs}"
