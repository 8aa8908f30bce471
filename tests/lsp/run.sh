#!/usr/bin/env bash
# The language server tests (lsp_test.mjs), as CTest runs them:
#   run.sh ARBITER SOURCE_DIR WORK_DIR
# WORK_DIR (under the build directory) keeps node_modules between runs: `npm ci` runs only when
# package-lock.json changed.
set -euo pipefail
arbiter=$1
source=$2
work=$3
mkdir -p "$work"
if ! cmp -s "$source/tests/lsp/package-lock.json" "$work/package-lock.json" ||
   [[ ! -d $work/node_modules/vscode-languageserver-protocol ]]; then
  cp "$source/tests/lsp/package.json" "$source/tests/lsp/package-lock.json" "$work/"
  (cd "$work" && npm ci --no-audit --no-fund --loglevel=error)
fi
export ARBITER=$arbiter ARBITER_SOURCE=$source NODE_MODULES=$work/node_modules
exec node --test "$source/tests/lsp/lsp_test.mjs"
