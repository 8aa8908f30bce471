#!/usr/bin/env bash
# The live Foxglove server seen by Foxglove's own client (foxglove_test.mjs), as CTest runs it:
#   foxglove_run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (BUILD/web) holds the node_modules that the build installed from web/package-lock.json
# (web/bundle.cmake); npm_ci_into installs it there if the build did not (tests/support/npm_ci.sh).
# Exits 77 (CTest: skipped) when this arbiter has no Foxglove server or the packages cannot be
# installed.
set -euo pipefail
arbiter=$1
source=$2
work=$3
# Only such a build holds this sentence (cli/server/foxglove_missing.cpp).
if grep -q "built without the Foxglove WebSocket server" "$arbiter"; then
  echo "SKIPPED: this arbiter was built without the Foxglove server (websocketpp)"
  exit 77
fi
. "$source/tests/support/npm_ci.sh"
if ! npm_ci_into "$source/web" "$work" node_modules/@foxglove/ws-protocol ||
    [[ ! -e $work/node_modules/@foxglove/ws-protocol || ! -e $work/node_modules/ajv ]]; then
  echo "SKIPPED: the node modules of web/package.json (@foxglove/ws-protocol, ajv, ws) are" \
       "missing from $work/node_modules and could not be installed"
  exit 77
fi
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
exec node --test "$source/web/tests/foxglove_test.mjs"
