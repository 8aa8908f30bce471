#!/usr/bin/env bash
# Neovim (headless, its built-in LSP client) on a broken copy of the soccer config:
#   nvim_test.sh ARBITER SOURCE_DIR
set -euo pipefail
arbiter=$1
source=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
sed 's/kick_ball => go_behind_ball/kick_bal => go_behind_ball/' \
  "$source/configs/soccer/walk_and_kick.yaml" >"$dir/walk_and_kick.yaml"
cd "$dir"
ARBITER=$arbiter CONFIG=$dir/walk_and_kick.yaml HOME=$dir XDG_CONFIG_HOME=$dir XDG_DATA_HOME=$dir \
  XDG_STATE_HOME=$dir timeout 60 nvim --headless --clean -c "luafile $source/tests/lsp/nvim_test.lua"
