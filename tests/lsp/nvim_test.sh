#!/usr/bin/env bash
# Neovim (headless, its built-in LSP client) with the set-up docs/editors.md gives, taken from that
# page, and then with the one-liner of `arbiter lsp --help`, on configs in a temporary folder:
#   nvim_test.sh ARBITER SOURCE_DIR
set -euo pipefail
arbiter=$(realpath "$1")
source=$(realpath "$2")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir -p "$dir/bin" "$dir/project/parts" "$dir/project/.git"  # .git: the project root
ln -s "$arbiter" "$dir/bin/arbiter"  # the docs' set-up runs `arbiter` from PATH
project=$dir/project
soccer=$source/configs/soccer/walk_and_kick.yaml
sed 's/kick_ball => go_behind_ball/kick_bal => go_behind_ball/' "$soccer" >"$project/walk_and_kick.yaml"
sed '/^plugins: \[soccer\]$/d' "$soccer" >"$project/without_plugins.yaml"
cp "$source/configs/paper/goalie_plan.yaml" "$project/goalie_plan.yaml"
cp "$source/configs/paper/walk_and_kick.yaml" "$project/paper.yaml"
printf '{\n  "name": "web",\n  "version": "1.0.0",\n  "dependencies": {"layers": "2"}\n}\n' \
  >"$project/package.json"
printf 'services:\n  web:\n    image: nginx\n' >"$project/docker-compose.yaml"
printf 'arbiter: 1\nname: m\ninclude: [parts/part.yaml]\nlayers:\n  - name: control\n' \
  >"$project/main.yaml"
printf 'layers:\n  - name: other\n    behaviours:\n      b: {type: scriptd}\n' \
  >"$project/parts/part.yaml"
mkdir "$project/cycle"
printf 'arbiter: 1\nname: r\ninclude: [a.yaml]\nlayers:\n  - name: top\n' >"$project/cycle/root.yaml"
printf 'include: [b.yaml]\nlayers:\n  - name: from_a\n' >"$project/cycle/a.yaml"
printf 'include: [root.yaml]\nlayers:\n  - name: from_b\n' >"$project/cycle/b.yaml"
# The first ```lua block of the Neovim section.
awk '/^## Neovim/ {section = 1} section && /^```lua/ {code = 1; next}
     code && /^```/ {exit} code {print}' "$source/docs/editors.md" >"$dir/init.lua"
[[ -s $dir/init.lua ]] || { echo "nvim_test: no lua block under '## Neovim' in docs/editors.md" >&2; exit 1; }
help_command=$("$arbiter" lsp --help | sed -n 's/^ *:lua /lua /p')
[[ -n $help_command ]] || { echo "nvim_test: no ':lua' line in 'arbiter lsp --help'" >&2; exit 1; }
cd "$project"
run() {
  PATH=$dir/bin:$PATH PROJECT=$project HELP_COMMAND=$help_command HOME=$dir XDG_CONFIG_HOME=$dir \
    XDG_DATA_HOME=$dir XDG_STATE_HOME=$dir timeout 60 nvim --headless --clean "$@" \
    -c "luafile $source/tests/lsp/nvim_test.lua"
}
MODE=docs run -c "luafile $dir/init.lua"
MODE=help run
