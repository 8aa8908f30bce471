#!/bin/bash
# Ctrl-C (or SIGTERM, as a service manager stops it) during `arbiter run --realtime` ends the run
# between two steps: exit 0, a summary, and a trace whose every line is a whole record, the last
# one the safe-value pass (the soccer demo stands: gait_velocity [0, 0, 0]).
set -eu
cli=$1
config=$2
signal=${3:-INT}
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$config" --realtime --steps 1000000 --trace "$work/trace.jsonl" >"$work/out.txt" &
pid=$!
# Wait (bounded) until a few steps are in the trace, then interrupt.
for _ in $(seq 1 200); do
  [ -f "$work/trace.jsonl" ] && [ "$(wc -l <"$work/trace.jsonl")" -ge 4 ] && break
  sleep 0.05
done
kill -"$signal" "$pid"
status=0
wait "$pid" || status=$?
pid=

[ "$status" -eq 0 ] || fail "exit status $status after SIG$signal"
grep -q '^interrupted: simulated' "$work/out.txt" || fail "no summary after the interrupt"
lines=$(wc -l <"$work/trace.jsonl")
[ "$lines" -ge 4 ] || fail "trace has only $lines lines"
[ "$(tail -c 1 "$work/trace.jsonl" | od -An -c | tr -d ' ')" = '\n' ] || fail "trace ends mid-line"
last=$(tail -n 1 "$work/trace.jsonl")
case "$last" in
  '{"step": '*'}}') ;;
  *) fail "last trace line is not a whole record: $last" ;;
esac
case "$last" in
  *'"safe": true'*'"gait_velocity": {"value": [0.0, 0.0, 0.0], "written": true}'*) ;;
  *) fail "last trace line is not the safe pass: $last" ;;
esac
grep -q 'safe values output: gait_velocity = \[0.0, 0.0, 0.0\]' "$work/out.txt" ||
  fail "the summary does not show the safe pass"
grep -q '^period jitter' "$work/out.txt" || fail "the summary has no timing"
steps=$(grep -c '^{"step": ' "$work/trace.jsonl")
[ "$steps" -eq $((lines - 1)) ] || fail "header plus $steps records != $lines lines"
echo "interrupted by SIG$signal after $steps steps: 1 passed, 0 failed"
