#!/bin/bash
# `arbiter dump --format dot` renders with Graphviz: every example config, and the multi-layer
# golden DOT file. Registered only where `dot` is installed.
set -eu
cli=$1
dot=$2
source_dir=$3
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cd "$source_dir"

passed=0
render() {  # render NAME DOT-FILE
  "$dot" -Tsvg "$2" -o "$work/$1.svg" 2>"$work/$1.err" || fail "dot rejected $1: $(cat "$work/$1.err")"
  [ ! -s "$work/$1.err" ] || fail "dot warned about $1: $(cat "$work/$1.err")"
  grep -q '<svg' "$work/$1.svg" || fail "no SVG for $1"
  passed=$((passed + 1))
}
for config in configs/paper/*.yaml; do
  name=$(basename "$config" .yaml)
  "$cli" dump "$config" --format dot >"$work/$name.dot" || fail "arbiter dump $config"
  render "$name" "$work/$name.dot"
done
"$cli" dump configs/paper/walk_and_kick.yaml --layer control --format dot >"$work/layer.dot"
render layer "$work/layer.dot"
render relay tests/data/golden/relay.dot
echo "rendered $passed graphs: 1 passed, 0 failed"
