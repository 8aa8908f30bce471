#!/bin/bash
# The bash completion script: commands, options, option values, and names read from a config.
set -eu
script=$1
cli=$2
source_dir=$3
cd "$source_dir"
# shellcheck source=/dev/null
source "$script"

failed=0
passed=0
# expect "WORDS..." -- EXPECTED...: completes the last word and compares the sorted replies.
expect() {
  local words=() expected=()
  while [[ $1 != -- ]]; do words+=("$1"); shift; done
  shift
  expected=("$@")
  COMP_WORDS=("$cli" "${words[@]}")
  COMP_CWORD=${#words[@]}
  COMPREPLY=()
  _arbiter
  local got want
  got=$(printf '%s\n' "${COMPREPLY[@]}" | sort | tr '\n' ' ')
  want=$(printf '%s\n' "${expected[@]}" | sort | tr '\n' ' ')
  if [[ $got == "$want" ]]; then
    passed=$((passed + 1))
  else
    echo "FAIL: arbiter ${words[*]}<TAB>: got [$got], want [$want]"
    failed=$((failed + 1))
  fi
}

expect "" -- validate run dump explain seek test plugins schema view edit plot replay diff lsp new
expect "n" -- new
expect "new" "" -- plugin
expect "new" "plugin" "rover" "configs/pa" -- configs/paper
expect "new" "--plugin-path" "configs" "plugin" "rover" "configs/so" -- configs/soccer
expect "new" "plugin" "" --
expect "replay" "--c" -- --config --color
expect "diff" "--t" -- --tolerance
expect "ex" -- explain
expect "seek" "--f" -- --from
expect "run" "--br" -- --break
expect "--log-level" "warn" "du" -- dump
expect "--plu" -- --plugin-path
expect "--max" -- --max-file-bytes
expect "--max-file-bytes" "1000" "va" -- validate
expect "dump" "--fo" -- --format
expect "dump" "--format" "" -- text dot json
expect "validate" "--format" "" -- text json
expect "--log-level" "" -- trace debug info warn error off
expect "dump" "configs/paper/walk_and_kick.yaml" "--layer" "" -- control
expect "explain" "configs/paper/walk_and_kick.yaml" "--trace" "x.jsonl" "--step" "3" "search" -- \
  search_for_ball
expect "explain" "configs/paper/walk_and_kick.yaml" "control/k" -- control/kick_ball
expect "explain" "configs/paper/goalie_plan.yaml" "go" -- goalie
expect "run" "configs/paper/walk_and_k" -- configs/paper/walk_and_kick.yaml \
  configs/paper/walk_and_kick.json
expect "plugins" "-" -- --format --load --builtin --help --log-level --plugin-path \
  --max-file-bytes --color
expect "run" "x.yaml" "--se" -- --serve --serve-token --serve-readonly
expect "edit" "-" -- --serve --serve-token --help --log-level --plugin-path --max-file-bytes --color
expect "edit" "configs/paper/walk_and_k" -- configs/paper/walk_and_kick.yaml \
  configs/paper/walk_and_kick.json
expect "run" "x.yaml" "--rt" -- --rt-priority
# Global options also after the command, as the parser takes them there.
expect "run" "x.yaml" "--plu" -- --plugin-path
expect "validate" "--c" -- --color
expect "explain" "x.yaml" "--m" -- --max-file-bytes
expect "run" "x.yaml" "--in" -- --inputs
expect "run" "x.yaml" "--fo" -- --foxglove
expect "replay" "x.mcap" "--fo" -- --foxglove
expect "run" "x.yaml" "--foxglove" "" --
expect "run" "x.yaml" "--rt-priority" "" --
# Each behaviour once, by its name; LAYER/NAME once a '/' is typed.
expect "explain" "configs/paper/walk_and_kick.yaml" "" -- go_behind_ball head_control kick_ball \
  search_for_ball
expect "explain" "configs/paper/walk_and_kick.yaml" "control/" -- control/go_behind_ball \
  control/head_control control/kick_ball control/search_for_ball
# A config whose plugin is found only through the --plugin-path typed on the command line.
plugin_dir=$(dirname "$cli")/../tests/plugins/lib
expect "--plugin-path" "$plugin_dir" "explain" "tests/data/plugins/good.yaml" "con" -- constant
expect "explain" "tests/data/plugins/good.yaml" "--plugin-path" "$plugin_dir" "con" -- constant
expect "view" "x.yaml" "--t" -- --trace
expect "plot" "--a" -- --actuators
expect "plot" "x.jsonl" "-o" "docs/walk_and_k" -- docs/walk_and_kick.svg
expect "run" "x.yaml" "--w" -- --watch
expect "run" "x.yaml" "--rec" -- --record --record-flush
expect "replay" "x.mcap" "--record-flush" "" --
expect "test" "--j" -- --junit
expect "test" "tests/scenarios/soccer/goalie_d" -- tests/scenarios/soccer/goalie_dives_at_the_shot.test.yaml
expect "ls" -- lsp
expect "lsp" "-" -- --help --log-level --plugin-path --max-file-bytes --color

echo "completion: $passed passed, $failed failed"
[[ $failed -eq 0 ]]
