#!/bin/bash
# `arbiter run --watch --realtime` on a copy of a config: a valid edit is swapped in while the
# run goes on (the diff is printed and the new behaviour shows in the run's events); a broken
# edit is reported with its file:line:col and the run goes on with the previous config; Ctrl-C
# still ends the run cleanly.
set -eu
cli=$1
config=$2
work=$(mktemp -d)
trap 'kill "$pid" 2>/dev/null || true; rm -rf "$work"' EXIT
cp "$config" "$work/robot.yaml"

"$cli" run "$work/robot.yaml" --watch --realtime --trace "$work/trace.jsonl" \
  >"$work/out.txt" 2>"$work/err.txt" &
pid=$!

fail() {
  echo "FAIL: $*"
  echo "--- stdout"; cat "$work/out.txt"
  echo "--- stderr"; cat "$work/err.txt"
  exit 1
}
# Waits (bounded: 10 s) until `grep -q PATTERN FILE` succeeds.
wait_for() {
  for _ in $(seq 1 200); do
    grep -q -- "$1" "$2" && return 0
    sleep 0.05
  done
  fail "no '$1' in $2"
}

wait_for 'control/head_control activated' "$work/out.txt"

# A valid edit: a new behaviour.
sed -i 's/^\(      head_control: .*\)$/\1\n      wave: {type: scripted, params: {activation: 1}}/' \
  "$work/robot.yaml"
wait_for 'control/wave activated' "$work/out.txt"
grep -q '^reload of .*robot.yaml: 1 change, swapped in at the next step$' "$work/out.txt" ||
  fail "no reload line"
grep -q '^  + behaviour control/wave (scripted)$' "$work/out.txt" || fail "no diff line"

# A broken edit: an unknown class, reported where it is written; the run goes on.
line=$(grep -n 'wave: ' "$work/robot.yaml" | cut -d: -f1)
sed -i 's/type: scripted, params: {activation: 1}/type: scriptd, params: {activation: 1}/' \
  "$work/robot.yaml"
wait_for 'rejected' "$work/err.txt"
grep -q "robot.yaml:$line:[0-9]*: error\[unknown-class\]: .*scriptd" "$work/err.txt" ||
  fail "the error does not name robot.yaml:$line"
grep -q 'still running the previous config' "$work/err.txt" || fail "no 'still running' line"
kill -0 "$pid" || fail "the run ended after the broken edit"

# The run went on with the previous config: the next valid edit (the behaviour removed) is taken.
sed -i '/wave: /d' "$work/robot.yaml"
wait_for '^  - behaviour control/wave (scripted)$' "$work/out.txt"
wait_for 'reloaded walk_and_kick: 2 layers, 4 behaviours' "$work/out.txt"

kill -INT "$pid"
status=0
wait "$pid" || status=$?
[ "$status" -eq 0 ] || fail "exit status $status after SIGINT"
grep -q '^interrupted: simulated .* (real time)$' "$work/out.txt" || fail "no summary"
grep -q '^  control/wave .*(removed by a reload)$' "$work/out.txt" || fail "no summary of wave"
# The trace records each swap with a header of the program that follows.
[ "$(grep -c '^{"arbiter_trace": 1, "reload": [12], "after_step": ' "$work/trace.jsonl")" -eq 2 ] ||
  fail "the trace does not have the two reload headers"
echo "watched: 2 edits swapped in, 1 broken edit rejected: 1 passed, 0 failed"
