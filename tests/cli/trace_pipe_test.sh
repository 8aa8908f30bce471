#!/bin/bash
# Traces and recordings read from a pipe (process substitution, /dev/stdin) as from a file.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
config=$source_dir/tests/data/replay/counter.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$config" --steps 30 -q --trace "$work/run.jsonl" --record "$work/run.mcap" ||
  fail "the run failed"

expect_exit 0 "$cli" diff <(cat "$work/run.jsonl") "$work/run.jsonl"
grep -q "identical: 30 steps" "$work/out.txt" || fail "diff of a trace from a pipe"
expect_exit 0 "$cli" diff <(cat "$work/run.mcap") "$work/run.jsonl"
grep -q "identical: 30 steps" "$work/out.txt" || fail "diff of a recording from a pipe"
"$cli" plot /dev/stdin -o "$work/run.svg" <"$work/run.jsonl" >"$work/out.txt" 2>"$work/err.txt" ||
  fail "plot of /dev/stdin"
[[ -s "$work/run.svg" ]] || fail "plot of /dev/stdin wrote no SVG"
cat "$work/run.mcap" | "$cli" plot /dev/stdin -o "$work/run2.svg" >"$work/out.txt" \
  2>"$work/err.txt" || fail "plot of a recording on /dev/stdin"
cmp -s "$work/run.svg" "$work/run2.svg" || fail "plot of the recording from a pipe differs"

echo ok
