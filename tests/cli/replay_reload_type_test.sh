#!/bin/bash
# A recorded hot reload that changes an interface actuator's type replays: the layers of the
# program the reload replaced are no longer fed the recorded inputs, which no longer fit them.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
work=$(mktemp -d)
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$work"' EXIT
cp "$source_dir/tests/data/replay/counter.yaml" "$work/robot.yaml"

# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$work/robot.yaml" --watch --realtime --record "$work/run.mcap" \
  >"$work/out.txt" 2>"$work/err.txt" &
pid=$!
wait_for 'control/steady activated' "$work/out.txt"
sed -i 's/count: {type: double}/count: {type: int}/' "$work/robot.yaml"
wait_for 'reloaded counter' "$work/out.txt"
sleep 0.3  # a few steps of the reloaded config
kill -INT "$pid"
wait "$pid" || fail "the recorded run failed"
pid=
grep -q 'actuator count: double -> int' "$work/out.txt" || fail "the reload did not change the type"

"$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl" >"$work/replay.txt" \
  2>"$work/replay_err.txt" || fail "replay did not repeat the run"
grep -q 'identical to the recording' "$work/replay.txt" || fail "replay is not identical"
grep -q '"reload": 1' "$work/replay.jsonl" || fail "the replay did not reload"
echo "ok"
