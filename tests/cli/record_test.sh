#!/bin/bash
# Recordings end to end on the soccer demos: record, replay (the run repeats itself), what-if
# replays with an edited graph and what `arbiter diff` says of them, a behaviour that is not
# deterministic caught by replay, a recording cut off by kill -9, and the tools that read traces
# reading recordings.
set -eu
cli=$1
source_dir=$2
test_plugins=$3
config=$source_dir/configs/soccer/walk_and_kick.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

expect_exit 0 "$cli" run "$config" --steps 220 -q --record "$work/run.mcap" --trace "$work/run.jsonl"
expect_exit 0 "$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl" --record "$work/replay.mcap"
grep -qx "replayed 220 steps of $work/run.mcap: identical to the recording" "$work/out.txt" ||
  fail "replay is not identical"
expect_exit 0 "$cli" diff "$work/run.mcap" "$work/replay.mcap" --format json
[[ $(cat "$work/out.txt") == '{"identical":true,"steps":[220,220],"first_divergence":null,"behaviours":{},"actuators":{},"machines":{}}' ]] ||
  fail "diff of a replay"
expect_exit 0 "$cli" diff "$work/run.jsonl" "$work/replay.mcap"

# The goalie demo: its world reports the shot in the input pass (step 201), the goalie its dive
# in the same step; replay reports the shot again in that pass, before the dive, as recorded.
goalie=$source_dir/configs/soccer/goalie.yaml
expect_exit 0 "$cli" run "$goalie" -q --record "$work/goalie.mcap"
expect_exit 0 "$cli" replay "$work/goalie.mcap"
grep -qx "replayed 240 steps of $work/goalie.mcap: identical to the recording" "$work/out.txt" ||
  fail "the goalie demo does not replay identically"

# Flat out, the run outpaces the recording's writer many times over and waits for it: every
# step is in the recording, and replaying it (flat out too) records every step again.
expect_exit 0 "$cli" run "$config" --steps 2000 -q --record "$work/long.mcap"
[[ ! -s "$work/err.txt" ]] || fail "a flat-out run dropped steps"
expect_exit 0 "$cli" replay "$work/long.mcap" --record "$work/long_replay.mcap"
grep -qx "replayed 2000 steps of $work/long.mcap: identical to the recording" "$work/out.txt" ||
  fail "a long flat-out recording does not replay whole"
expect_exit 0 "$cli" diff "$work/long.mcap" "$work/long_replay.mcap"
grep -q "identical: 2000 steps" "$work/out.txt" || fail "the long replay's recording"

# What if: kick_ball removed, then the kick_ball => go_behind_ball inhibition flipped.
sed -e '/kick_ball: {type/d' -e '/kick_ball => go_behind_ball/d' "$config" >"$work/no_kick.yaml"
sed -e 's/- kick_ball => go_behind_ball/- go_behind_ball => kick_ball/' "$config" >"$work/flipped.yaml"
expect_exit 0 "$cli" --plugin-path "$(dirname "$cli")/../plugins" replay "$work/run.mcap" \
  --config "$work/no_kick.yaml" --record "$work/no_kick.mcap"
expect_exit 1 "$cli" diff "$work/run.mcap" "$work/no_kick.mcap" --format json
grep -q '"first_divergence":{"step":171,"what":\["control/go_behind_ball","control/kick_ball",' "$work/out.txt" ||
  fail "the removed behaviour is not named at its first divergence"
grep -q '"control/kick_ball":{"differ":1,"first":171,"last":171}' "$work/out.txt" ||
  fail "kick_ball's count"
expect_exit 0 "$cli" replay "$work/run.mcap" --config "$work/flipped.yaml" --trace "$work/flipped.jsonl"
expect_exit 1 "$cli" diff "$work/run.mcap" "$work/flipped.jsonl"
grep -q "^first divergence: step 171: control/go_behind_ball, control/kick_ball" "$work/out.txt" ||
  fail "the flipped inhibition"

# An edited config without a place for a recorded input.
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 0 "$cli" run \
  "$source_dir/tests/data/replay/counter.yaml" --steps 5 -q --record "$work/counter.mcap"
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 0 "$cli" replay "$work/counter.mcap"
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 1 "$cli" replay "$work/counter.mcap" \
  --config "$source_dir/tests/data/replay/counter_renamed.yaml"
grep -qx "$source_dir/tests/data/replay/counter_renamed.yaml:3:1: error: recorded input 'count' has no place in this config: no interface layer declares an actuator 'count'" \
  "$work/err.txt" || fail "a recorded input without a place"

# Two interface layers that report: each replays its own reports, so the replay is identical.
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 0 "$cli" run \
  "$source_dir/tests/data/replay/two_counters.yaml" --steps 6 -q --record "$work/two.mcap"
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 0 "$cli" replay "$work/two.mcap" --trace "$work/two.jsonl"
grep -qx "replayed 6 steps of $work/two.mcap: identical to the recording" "$work/out.txt" ||
  fail "a replay of two reporting interface layers is not identical"
grep -q '"reported": \[{"by": "left", "text": "left ticked"}, {"by": "right", "text": "right ticked"}\]' \
  "$work/two.jsonl" || fail "the replayed reports are not each layer's own"

# Two runs on one timeline: the second run's row under each behaviour's, divergent steps shaded.
expect_exit 0 "$cli" plot "$work/run.mcap" --compare "$work/no_kick.mcap" -o "$work/compare.svg"
[[ $(grep -o 'class="row behaviour compared" data-name="control/kick_ball"' "$work/compare.svg" | wc -l) -eq 1 ]] ||
  fail "no second row for kick_ball"
[[ $(grep -o '<title>step 171: the runs differ</title>' "$work/compare.svg" | wc -l) -eq 2 ]] ||
  fail "the divergent steps are not marked"

# A behaviour that is not deterministic is caught and named.
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 0 "$cli" run \
  "$source_dir/tests/data/replay/unsteady.yaml" --steps 20 -q --record "$work/unsteady.mcap"
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 1 "$cli" replay "$work/unsteady.mcap"
grep -qx "$work/unsteady.mcap: error: the replay differs from the recording at step 1: control/dice" \
  "$work/err.txt" || fail "the unsteady behaviour is not named"

# Cut off while written: readable up to its last complete chunk, and every reader says so.
"$cli" run "$config" --steps 100000000 -q --record "$work/cut.mcap" >/dev/null 2>&1 &
pid=$!
for _ in $(seq 1 600); do  # up to 30 s on a busy machine
  [[ $(stat -c %s "$work/cut.mcap" 2>/dev/null || echo 0) -gt 300000 ]] && break
  sleep 0.05
done
kill -9 "$pid"
wait "$pid" 2>/dev/null || true
pid=
expect_exit 0 "$cli" replay "$work/cut.mcap"
grep -q "cut.mcap: warning: the recording was cut off while it was written: it ends after step " \
  "$work/err.txt" || fail "replay of a cut recording"
grep -q "identical to the recording" "$work/out.txt" || fail "replay of a cut recording"
expect_exit 0 "$cli" diff "$work/cut.mcap" "$work/cut.mcap"
grep -q "warning: the recording was cut off" "$work/err.txt" || fail "diff of a cut recording"
expect_exit 0 "$cli" plot "$work/cut.mcap" -o "$work/cut.svg"
grep -q "warning: the recording was cut off" "$work/err.txt" || fail "plot of a cut recording"
# view serves until stopped: wait for its warning (a loaded machine may take a while), then stop it.
serve_until "warning: the recording was cut off" "$cli" view "$config" --trace "$work/cut.mcap" \
  --serve 0
grep -q "warning: the recording was cut off" "$work/err.txt" || fail "view of a cut recording"

# explain and plot read recordings as they read traces.
expect_exit 0 "$cli" explain "$config" --trace "$work/run.mcap" --step 8 search_for_ball
cp "$work/out.txt" "$work/explain_mcap.txt"
expect_exit 0 "$cli" explain "$config" --trace "$work/run.jsonl" --step 8 search_for_ball
cmp -s "$work/out.txt" "$work/explain_mcap.txt" || fail "explain of a recording"
expect_exit 0 "$cli" plot "$work/run.mcap" -o "$work/mcap.svg"
expect_exit 0 "$cli" plot "$work/run.jsonl" -o "$work/jsonl.svg"
cmp -s "$work/mcap.svg" "$work/jsonl.svg" || fail "plot of a recording"
echo ok
