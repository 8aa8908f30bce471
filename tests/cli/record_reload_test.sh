#!/bin/bash
# A recorded run with a hot reload replays identically: `arbiter run --watch --record` keeps the
# reloaded config's files, and `arbiter replay` reloads them after the same step. With --config
# the recorded reloads are not applied, and replay says so.
set -eu
cli=$1
config=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cp "$config" "$work/robot.yaml"

record_reload 'control/head_control activated' \
  's/^\(      head_control: .*\)$/\1\n      wave: {type: scripted, params: {activation: 1}}/' \
  'control/wave activated'

# The edit is gone from disk: replay must take the reloaded config from the recording.
cp "$config" "$work/robot.yaml"
expect_exit 0 "$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl"
grep -q 'identical to the recording' "$work/out.txt" || fail "replay is not identical"
grep -q '"reload": 1' "$work/replay.jsonl" || fail "the replay did not reload"
grep -q '"wave"' "$work/replay.jsonl" || fail "the reloaded behaviour did not run in the replay"
if grep -q 'warning' "$work/err.txt"; then fail "replay warned"; fi

# An edited graph runs alone, noted.
"$cli" replay "$work/run.mcap" --config "$work/robot.yaml" >"$work/whatif.txt" \
  2>"$work/whatif_err.txt" || fail "the what-if replay failed"
grep -q 'note: the config was reloaded after step [0-9]*; with --config the recorded reloads are not applied' \
  "$work/whatif_err.txt" || fail "no note about the recorded reloads"
echo "ok"
