#!/bin/bash
# A recorded input of every built-in value type replays as recorded: each value is converted from
# the recording's message into its actuator's type, whatever the type, and the replay's steps are
# the run's.
set -eu
cli=$1
source_dir=$2
config=$source_dir/tests/data/replay/kinds.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

expect_exit 0 "$cli" run "$config" --steps 4 -q --inputs "$source_dir/tests/data/replay/kinds_inputs.yaml" \
  --record "$work/kinds.mcap" --trace "$work/kinds.jsonl"
# What the run's interface wrote is what the inputs file gave.
grep -q '"label": {"value": "a \\"quoted\\" name, with ünïcode", "written": true}' "$work/kinds.jsonl" ||
  fail "the run did not write the quoted label"
grep -q '"count": {"value": -9007199254740993, "written": true}' "$work/kinds.jsonl" ||
  fail "the run did not write the large count"
expect_exit 0 "$cli" replay "$work/kinds.mcap" --trace "$work/replayed.jsonl"
grep -q "replayed 4 steps of .*: identical to the recording" "$work/out.txt" ||
  fail "the replay differs from the recording"
expect_exit 0 "$cli" diff "$work/kinds.jsonl" "$work/replayed.jsonl"
echo ok
