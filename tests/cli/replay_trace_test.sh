#!/bin/bash
# `arbiter replay --trace FILE` puts FILE in place once the replay has run: a replay that fails
# part way (here, on a recording damaged in its middle) leaves FILE as it was, and no partial
# file beside it.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
config=$source_dir/tests/data/replay/counter.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$config" --steps 3000 -q --record "$work/run.mcap" || fail "the run failed"
"$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl" >"$work/out.txt" 2>"$work/err.txt" ||
  fail "the replay failed"
grep -q '"step": 3000' "$work/replay.jsonl" || fail "the replay's trace is not whole"

# 30000 bytes over the middle of the recording: whatever they hit past its first chunks (a
# chunk, its length), the replay fails there, after it has stepped.
size=$(stat -c %s "$work/run.mcap")
cp "$work/run.mcap" "$work/bad.mcap"
head -c 30000 /dev/zero | tr '\0' '\377' |
  dd of="$work/bad.mcap" bs=1 seek=$((size / 3)) conv=notrunc 2>/dev/null
echo previous >"$work/trace.jsonl"
expect_exit 1 "$cli" replay "$work/bad.mcap" --trace "$work/trace.jsonl"
grep -q "bad.mcap: error: at byte" "$work/err.txt" || fail "no error where the recording is damaged"
[[ $(cat "$work/trace.jsonl") == previous ]] || fail "the failed replay changed the trace file"
leftover=$(find "$work" -name '*.partial')
[[ -z $leftover ]] || fail "a partial trace is left: $leftover"
echo ok
