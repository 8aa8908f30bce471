#!/bin/bash
# A recorded run with a hot reload replays identically: `arbiter run --watch --record` keeps the
# reloaded config's files, and `arbiter replay` reloads them after the same step. With --config
# the recorded reloads are not applied, and replay says so.
set -eu
cli=$1
config=$2
work=$(mktemp -d)
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
cp "$config" "$work/robot.yaml"

# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$work/robot.yaml" --watch --realtime --record "$work/run.mcap" \
  >"$work/out.txt" 2>"$work/err.txt" &
pid=$!
wait_for 'control/head_control activated' "$work/out.txt"
sed -i 's/^\(      head_control: .*\)$/\1\n      wave: {type: scripted, params: {activation: 1}}/' \
  "$work/robot.yaml"
wait_for 'control/wave activated' "$work/out.txt"
sleep 0.3  # a few steps of the reloaded config
kill -INT "$pid"
wait "$pid" || fail "the recorded run failed"
pid=

# The edit is gone from disk: replay must take the reloaded config from the recording.
cp "$config" "$work/robot.yaml"
"$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl" >"$work/replay.txt" \
  2>"$work/replay_err.txt" || fail "replay did not repeat the run"
grep -q 'identical to the recording' "$work/replay.txt" || fail "replay is not identical"
grep -q '"reload": 1' "$work/replay.jsonl" || fail "the replay did not reload"
grep -q '"wave"' "$work/replay.jsonl" || fail "the reloaded behaviour did not run in the replay"
if grep -q 'warning' "$work/replay_err.txt"; then fail "replay warned"; fi

# An edited graph runs alone, noted.
"$cli" replay "$work/run.mcap" --config "$work/robot.yaml" >"$work/whatif.txt" \
  2>"$work/whatif_err.txt" || fail "the what-if replay failed"
grep -q 'note: the config was reloaded after step [0-9]*; with --config the recorded reloads are not applied' \
  "$work/whatif_err.txt" || fail "no note about the recorded reloads"
echo "ok"
