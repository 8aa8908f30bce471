#!/usr/bin/env bash
# The language server tests (lsp_test.mjs), as CTest runs them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (under the build directory) keeps node_modules between runs (tests/support/npm_ci.sh).
set -euo pipefail
arbiter=$1
source=$2
work=$3
. "$source/tests/support/npm_ci.sh"
npm_ci_into "$source/tests/lsp" "$work" node_modules/vscode-languageserver-protocol
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
exec node --test "$source/tests/lsp/lsp_test.mjs"
