#!/usr/bin/env bash
# Recordings read by @mcap/core, as CTest runs them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR [TEST]
# TEST: the node test file of tests/mcap to run (default mcap_test.mjs).
# WORK_DIR (under the build directory) keeps node_modules between runs (tests/support/npm_ci.sh).
set -euo pipefail
arbiter=$1
source=$2
work=$3
tests=${4:-mcap_test.mjs}
. "$source/tests/support/npm_ci.sh"
npm_ci_into "$source/tests/mcap" "$work" node_modules/ajv
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
exec node --test "$source/tests/mcap/$tests"
