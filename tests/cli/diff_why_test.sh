#!/bin/bash
# `arbiter diff` says why two runs part, checked against golden files (tests/data/golden/diff/):
# the docs' what-if without kick_ball (the same inputs met a different graph), a seed change (the
# inputs differed first) and a param change in a state machine. Then explain and view of a
# recording without a config (the one it holds) and with one that is not its own.
# ARBITER_UPDATE_GOLDEN=1 rewrites the golden files instead of comparing.
set -eu
cli=$1
source_dir=$2
test_plugins=$3
golden=$source_dir/tests/data/golden/diff
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
export ARBITER_PLUGIN_PATH=$(dirname "$cli")/../plugins

# check NAME: out.txt is the golden file NAME.
check() {
  if [[ -n ${ARBITER_UPDATE_GOLDEN:-} ]]; then
    cp "$work/out.txt" "$golden/$1"
    return
  fi
  diff -u "$golden/$1" "$work/out.txt" >"$work/golden_diff.txt" || fail "$1 differs from its golden file"
}

# Relative names in the work folder, so that the output names the files alike on every machine.
cd "$work"
cp "$source_dir/configs/soccer/walk_and_kick.yaml" walk_and_kick.yaml
sed -e '/kick_ball: {type/d' -e '/kick_ball => go_behind_ball/d' walk_and_kick.yaml >no_kick.yaml
sed -e 's/seed: 7/seed: 8/' walk_and_kick.yaml >seed8.yaml
cp "$source_dir/configs/paper/hierarchical.yaml" match.yaml
sed -e 's/dribble: {type: scripted, params: {hold: 3}}/dribble: {type: scripted, params: {hold: 5}}/' \
  match.yaml >match_hold5.yaml
grep -q 'hold: 5' match_hold5.yaml || fail "the edit of hierarchical.yaml did not apply"

expect_exit 0 "$cli" run walk_and_kick.yaml --steps 220 -q --record run.mcap --trace run.jsonl
expect_exit 0 "$cli" replay run.mcap --config no_kick.yaml --record no_kick.mcap
expect_exit 0 "$cli" run seed8.yaml --steps 220 -q --record seed8.mcap
expect_exit 0 "$cli" run match.yaml --steps 20 -q --record match.mcap
expect_exit 0 "$cli" run match_hold5.yaml --steps 20 -q --record match_hold5.mcap

# The what-if: the same inputs met a graph without kick_ball.
expect_exit 1 "$cli" diff run.mcap no_kick.mcap
check no_kick.txt
expect_exit 1 "$cli" diff run.mcap no_kick.mcap --format json
check no_kick.json
# A seed change: the world's inputs differed first.
expect_exit 1 "$cli" diff run.mcap seed8.mcap
check seed.txt
# A state's param changed: the state machine parts first.
expect_exit 1 "$cli" diff match.mcap match_hold5.mcap
check state_param.txt
# A trace holds neither its inputs apart nor its config: said, and the recording side explained.
expect_exit 1 "$cli" diff run.jsonl no_kick.mcap
check trace_and_recording.txt

# A trace beside a recording: the recording's config names the inputs in the trace's records.
expect_exit 0 "$cli" run seed8.yaml --steps 220 -q --trace seed8.jsonl
expect_exit 1 "$cli" diff seed8.jsonl run.mcap
grep -qx "inputs: they differed first, at step 3 (ball_position), read before the step's behaviours ran: the runs met different inputs (the inputs B's config names)" \
  "$work/out.txt" || fail "diff of a trace and a recording whose inputs differ"

# One run only goes on longer: said so, and no cause is made up.
expect_exit 0 "$cli" replay run.mcap --steps 200 --record short.mcap
expect_exit 1 "$cli" diff run.mcap short.mcap
grep -qx "the runs agree on every step both have; only A has step 201 (A has 220 steps, B 200)" \
  "$work/out.txt" || fail "diff of a run and a shorter replay of it"
! grep -q "^inputs:" "$work/out.txt" || fail "diff of a shorter run says something of its inputs"

# The same inputs and the same config, yet the runs differ: something is not deterministic.
cp "$source_dir/tests/data/replay/unsteady.yaml" unsteady.yaml
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 0 "$cli" run unsteady.yaml --steps 20 -q --record unsteady.mcap
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 1 "$cli" replay unsteady.mcap --record unsteady_again.mcap
ARBITER_PLUGIN_PATH=$test_plugins expect_exit 1 "$cli" diff unsteady.mcap unsteady_again.mcap
grep -qx "inputs: the same up to step 1: the same inputs met the same config, so something in the run is not deterministic (a behaviour, state or plugin; docs/replay.md, Determinism)" \
  "$work/out.txt" || fail "diff of a run that is not deterministic"
grep -qx "config: the same in A and B" "$work/out.txt" || fail "diff of two runs of one config"

# explain and view of a recording: without a config, the one it holds.
expect_exit 0 "$cli" explain --trace run.mcap --step 171 kick_ball
check explain_recorded.txt
# view serves a recording with the config it holds.
"$cli" view --trace run.mcap --serve 0 >"$work/out.txt" 2>"$work/err.txt" &
pid=$!
wait_for "viewing run.mcap (220 steps of walk_and_kick) at http" "$work/out.txt"
kill "$pid"
wait "$pid" 2>/dev/null || true
pid=
# With one that is not its own: what the recording holds, and how the given one differs.
expect_exit 1 "$cli" explain no_kick.yaml --trace run.mcap --step 171 go_behind_ball
cp "$work/err.txt" "$work/out.txt"
check explain_mismatch.txt
expect_exit 1 "$cli" view no_kick.yaml --trace run.mcap --serve 0
grep -q "^run.mcap: error\[config-mismatch\]: the recording was made with another config than no_kick.yaml" \
  "$work/err.txt" || fail "view accepts a config that is not the recording's"
! grep -q "MCAP" "$work/err.txt" || fail "view quotes the recording's bytes"
# A config that differs from the recording's only in its layout of layers is refused too, and the
# recording's header is not quoted as a source line.
expect_exit 1 "$cli" view "$source_dir/configs/paper/walk_and_kick.yaml" --trace run.mcap --serve 0
! grep -q "MCAP" "$work/err.txt" || fail "view quotes the recording's bytes as a source line"
# A pipe is read once: with a config, explain reads it as before; without, it asks for a file.
expect_exit 0 "$cli" explain walk_and_kick.yaml --trace <(cat run.mcap) --step 171 kick_ball
cmp -s "$work/out.txt" "$golden/explain_recorded.txt" || fail "explain of a recording read from a pipe"
expect_exit 2 "$cli" explain --trace <(cat run.mcap) --step 171 kick_ball
grep -q "is not a file (a pipe?): a recording's config is read from it before its steps" "$work/err.txt" ||
  fail "explain of a piped recording without a config"
expect_exit 1 "$cli" diff <(cat run.mcap) no_kick.mcap
grep -q "^config: not known: A is not a file (a pipe?), read once already by the diff" "$work/out.txt" ||
  fail "diff of a piped recording"
# A config without a target: the target was forgotten, not the config.
expect_exit 2 "$cli" explain walk_and_kick.yaml --trace run.mcap --step 171
grep -q "name the behaviour, state machine, actuator or state to explain" "$work/err.txt" || fail "explain without a target"
# A trace holds no config.
expect_exit 2 "$cli" explain --trace run.jsonl --step 171 kick_ball
grep -q "run.jsonl is a trace, which holds no config" "$work/err.txt" || fail "explain of a trace without a config"

# plot --compare: B's rows under A's for state machines and actuators too, A and B named.
expect_exit 0 "$cli" plot match.mcap --compare match_hold5.mcap -o compare.svg
grep -q 'class="row controller compared" data-name="state_machines/attack_plan"' compare.svg ||
  fail "plot --compare: no B row for the state machine"
grep -q '<title>step 9: the runs differ</title>' compare.svg ||
  fail "plot --compare: the state machine's first divergent step is not shaded"
grep -q 'A: match.mcap (20 steps), B: match_hold5.mcap (20 steps)' compare.svg ||
  fail "plot --compare does not name A and B"
expect_exit 0 "$cli" plot run.mcap --compare no_kick.mcap --actuators -o compare.svg
grep -q 'class="row actuator compared" data-name="kick"' compare.svg ||
  fail "plot --compare: no B row for an actuator"
[[ $(grep -o '<title>step 220: the runs differ</title>' compare.svg | wc -l) -eq 1 ]] ||
  fail "plot --compare: the kick actuator's last divergent step is not shaded once"
echo ok
