#!/usr/bin/env bash
# The recording read by @mcap/core (mcap_test.mjs), as CTest runs it:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (under the build directory) keeps node_modules between runs: `npm ci` runs only when
# package-lock.json changed.
set -euo pipefail
arbiter=$1
source=$2
work=$3
mkdir -p "$work"
if ! cmp -s "$source/tests/mcap/package-lock.json" "$work/package-lock.json" ||
   [[ ! -d $work/node_modules/@mcap/core ]]; then
  cp "$source/tests/mcap/package.json" "$source/tests/mcap/package-lock.json" "$work/"
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
fi
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
exec node --test "$source/tests/mcap/mcap_test.mjs"
