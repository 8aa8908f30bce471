#!/bin/bash
# `arbiter run --watch --realtime` on a copy of a config: a valid edit is swapped in while the
# run goes on (the diff is printed and the new behaviour shows in the run's events); a broken
# edit is reported with its file:line:col and the run goes on with the previous config; Ctrl-C
# still ends the run cleanly.
set -eu
cli=$1
config=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cp "$config" "$work/robot.yaml"

"$cli" run "$work/robot.yaml" --watch --realtime --trace "$work/trace.jsonl" \
  >"$work/out.txt" 2>"$work/err.txt" &
pid=$!

wait_for 'control/head_control activated' "$work/out.txt"

# A valid edit: a new behaviour.
sed -i 's/^\(      head_control: .*\)$/\1\n      wave: {type: scripted, params: {activation: 1}}/' \
  "$work/robot.yaml"
wait_for 'control/wave activated' "$work/out.txt"
grep -q '^reload of .*robot.yaml: 1 change, swapped in at the next step$' "$work/out.txt" ||
  fail "no reload line"
grep -q '^  + behaviour control/wave (scripted)$' "$work/out.txt" || fail "no diff line"

# A params edit: the diff gives the param's old and new value.
sed -i 's/turn_rate: 0.6/turn_rate: 0.5/' "$work/robot.yaml"
wait_for '^  ~ behaviour control/search_for_ball: params: turn_rate 0.6 -> 0.5$' "$work/out.txt"

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
pid=
[ "$status" -eq 0 ] || fail "exit status $status after SIGINT"
grep -q '^interrupted: simulated .* (real time)$' "$work/out.txt" || fail "no summary"
grep -q '^  control/wave .*(removed by a reload)$' "$work/out.txt" || fail "no summary of wave"
# The trace records each swap with a header of the program that follows.
[ "$(grep -c '^{"arbiter_trace": 1, "reload": [12], "after_step": ' "$work/trace.jsonl")" -eq 2 ] ||
  fail "the trace does not have the two reload headers"
# Not a terminal: no status line, no terminal control in the output.
! grep -q 'watching' "$work/out.txt" "$work/err.txt" || fail "a status line outside a terminal"
! grep -q $'\r' "$work/out.txt" "$work/err.txt" || fail "a carriage return outside a terminal"

# In a terminal (a pty from script(1)): the status line, rewritten in place, names the config,
# the step and the last reload; every other line starts on a cleared line. A machine without
# pseudo-terminals (a chroot without /dev/pts) cannot show it: that part is skipped, and says so.
terminal="the status line in a terminal: 1 passed, 0 failed"
if ! command -v script >/dev/null; then
  terminal="the status line in a terminal: skipped (no script(1))"
elif ! script -qec true /dev/null >/dev/null 2>&1; then
  terminal="the status line in a terminal: skipped (no pseudo-terminal here)"
else
  cp "$config" "$work/tty.yaml"
  ARBITER_CLI="$cli" CONFIG="$work/tty.yaml" script -qfec \
    'timeout -s INT 3 "$ARBITER_CLI" run "$CONFIG" --watch --realtime' /dev/null \
    >"$work/tty.txt" 2>&1 &
  tty_pid=$!
  sleep 1.5
  sed -i 's/turn_rate: 0.6/turn_rate: 0.5/' "$work/tty.yaml"
  wait "$tty_pid" || true
  grep -q $'\r\e\[Kwatching .*tty.yaml — step [0-9]*, no reload yet' "$work/tty.txt" ||
    fail "no status line before the reload: $(cat -v "$work/tty.txt" | head -5)"
  grep -q $'\r\e\[Kwatching .*tty.yaml — step [0-9]*, last reload at step [0-9]' "$work/tty.txt" ||
    fail "no status line after the reload: $(cat -v "$work/tty.txt" | tail -5)"
  grep -q $'\r\e\[Kreload of .*tty.yaml: 1 change' "$work/tty.txt" ||
    grep -q $'^reload of .*tty.yaml: 1 change' "$work/tty.txt" || fail "no reload line in the terminal"
  # The status line never runs into another line: it is followed by a clear (or its redraw).
  ! grep -aqP 'watching [^\r\n]*?(no reload yet|last reload at step \d+)[^\r\d]' "$work/tty.txt" ||
    fail "a line written over the status line"
fi
echo "watched: 3 edits swapped in, 1 broken edit rejected, $terminal"
