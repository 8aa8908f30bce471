#!/bin/bash
# Ctrl-C during `arbiter run --realtime` ends the run between two steps: exit 0, a summary, and a
# trace whose every line is a whole record.
set -eu
cli=$1
config=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$cli" run "$config" --realtime --steps 1000000 --trace "$work/trace.jsonl" >"$work/out.txt" &
pid=$!
# Wait (bounded) until a few steps are in the trace, then interrupt.
for _ in $(seq 1 200); do
  [ -f "$work/trace.jsonl" ] && [ "$(wc -l <"$work/trace.jsonl")" -ge 4 ] && break
  sleep 0.05
done
kill -INT "$pid"
status=0
wait "$pid" || status=$?

fail() { echo "FAIL: $*"; cat "$work/out.txt"; exit 1; }
[ "$status" -eq 0 ] || fail "exit status $status after SIGINT"
grep -q '^interrupted: simulated' "$work/out.txt" || fail "no summary after the interrupt"
lines=$(wc -l <"$work/trace.jsonl")
[ "$lines" -ge 4 ] || fail "trace has only $lines lines"
[ "$(tail -c 1 "$work/trace.jsonl" | od -An -c | tr -d ' ')" = '\n' ] || fail "trace ends mid-line"
last=$(tail -n 1 "$work/trace.jsonl")
case "$last" in
  '{"step": '*'}}') ;;
  *) fail "last trace line is not a whole record: $last" ;;
esac
steps=$(grep -c '^{"step": ' "$work/trace.jsonl")
[ "$steps" -eq $((lines - 1)) ] || fail "header plus $steps records != $lines lines"
echo "interrupted after $steps steps: 1 passed, 0 failed"
