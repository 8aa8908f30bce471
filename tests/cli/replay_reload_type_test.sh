#!/bin/bash
# A recorded hot reload that changes an interface actuator's type replays: the layers of the
# program the reload replaced are no longer fed the recorded inputs, which no longer fit them.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cp "$source_dir/tests/data/replay/counter.yaml" "$work/robot.yaml"

record_reload 'control/steady activated' 's/count: {type: double}/count: {type: int}/' \
  'reloaded counter'
grep -q 'actuator count: double -> int' "$work/out.txt" || fail "the reload did not change the type"

expect_exit 0 "$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl"
grep -q 'identical to the recording' "$work/out.txt" || fail "replay is not identical"
grep -q '"reload": 1' "$work/replay.jsonl" || fail "the replay did not reload"
echo "ok"
