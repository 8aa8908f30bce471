#!/usr/bin/env bash
# The browser tests of the web view (browser_test.mjs), as CTest runs them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (under the build directory) keeps node_modules between runs (tests/support/npm_ci.sh).
# ARBITER_SCREENSHOT=docs/live_view.png also saves the README's screenshot of the soccer demo.
set -euo pipefail
arbiter=$1
source=$2
work=$3
. "$source/tests/support/npm_ci.sh"
npm_ci_into "$source/tests/web" "$work" node_modules/playwright-core
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
export CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
exec node --test "$source/tests/web/browser_test.mjs"
