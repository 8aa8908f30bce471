#!/usr/bin/env bash
# The browser tests of the web view (browser_test.mjs), as CTest runs them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (under the build directory) keeps node_modules between runs: `npm ci` runs only when
# package-lock.json changed, so a second run downloads nothing.
# ARBITER_SCREENSHOT=docs/live_view.png also saves the README's screenshot of the soccer demo.
set -euo pipefail
arbiter=$1
source=$2
work=$3
mkdir -p "$work"
if ! cmp -s "$source/tests/web/package-lock.json" "$work/package-lock.json" ||
   [[ ! -d $work/node_modules/playwright-core ]]; then
  cp "$source/tests/web/package.json" "$source/tests/web/package-lock.json" "$work/"
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
fi
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
export CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
exec node --test "$source/tests/web/browser_test.mjs"
