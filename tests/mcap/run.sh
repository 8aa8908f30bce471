#!/usr/bin/env bash
# The recording read by @mcap/core (mcap_test.mjs), as CTest runs it:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (under the build directory) keeps node_modules between runs (tests/support/npm_ci.sh).
set -euo pipefail
arbiter=$1
source=$2
work=$3
. "$source/tests/support/npm_ci.sh"
npm_ci_into "$source/tests/mcap" "$work" node_modules/@mcap/core
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
exec node --test "$source/tests/mcap/mcap_test.mjs"
