#!/usr/bin/env bash
# Soak test of `arbiter run` (docs/robustness.md; not part of the test suite: it takes a while).
# Runs the soccer demo flat out for STEPS steps (default 10 000 000) with the live view served
# and one client streaming it, the config edited every 10 s (hot reload through --watch) and a
# trace written to a temporary directory (deleted afterwards). Passes when the run exits 0 with
# nothing on stderr, every reload applied, the trace holds every step once and in order, and the
# resident memory after warm-up (the first tenth of the steps) stays within 1 MiB.
#
#   scripts/soak.sh [BUILD_DIR] [STEPS]      # BUILD_DIR defaults to build/dev
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${1:-build/dev}
steps=${2:-10000000}
cli=$build/cli/arbiter
[ -x "$cli" ] || { echo "soak: no $cli; build first" >&2; exit 2; }

# The scratch folder `work`, and the processes in `pids` killed at exit.
# shellcheck source=../tests/cli/expect.sh
source tests/cli/expect.sh

# A soccer step record is about 1 KB: make sure the trace fits, with room to spare.
need_kb=$((steps * 11 / 10 + 1048576))
free_kb=$(df -Pk "$work" | awk 'NR == 2 {print $4}')
if [ "$free_kb" -lt "$need_kb" ]; then
  echo "soak: $((need_kb / 1048576)) GiB needed in $work for the trace, $((free_kb / 1048576)) GiB free" >&2
  exit 2
fi

config=$work/walk_and_kick.yaml
cp configs/soccer/walk_and_kick.yaml "$config"
grep -q 'turn_rate: 0.6' "$config" || { echo "soak: the demo's turn_rate is not 0.6" >&2; exit 2; }
token=soak-$(od -An -N8 -tx1 /dev/urandom | tr -d ' \n')

started=$(date +%s)
ARBITER_SERVE_TOKEN=$token "$cli" run "$config" --plugin-path "$build/plugins" --steps "$steps" \
  --full-speed --serve 127.0.0.1:0 --watch --trace "$work/trace.jsonl" --quiet \
  >"$work/out.txt" 2>"$work/err.txt" &
run_pid=$!
pids+=("$run_pid")

url=$(printed 's/^serving the live view at (http[^ ?]*).*/\1/p' "$work/out.txt")
[ -n "$url" ] || { echo "soak: the live view did not start" >&2; cat "$work/err.txt" >&2; exit 1; }
curl -sN -H "X-Arbiter-Token: $token" "${url}events" | wc -c >"$work/client_bytes" &
pids+=($!)

rss_kb() { awk '/^VmRSS:/ {print $2}' "/proc/$run_pid/status" 2>/dev/null || true; }
samples=$work/rss.txt
edits=0
next_edit=$((started + 10))
rate=0.6
elapsed=
while kill -0 "$run_pid" 2>/dev/null; do
  if [ -z "$elapsed" ] && grep -q '^the run is over' "$work/out.txt"; then
    # After the last step the live view stays up until Ctrl-C.
    elapsed=$(($(date +%s) - started))
    kill -INT "$run_pid"
  fi
  step=$(tail -c 4096 "$work/trace.jsonl" 2>/dev/null | sed -nE 's/^\{"step": ([0-9]+).*/\1/p' | tail -1)
  rss=$(rss_kb)
  [ -n "$rss" ] && [ -n "$step" ] && echo "$(($(date +%s) - started)) $step $rss" >>"$samples"
  if [ "$(date +%s)" -ge "$next_edit" ]; then
    # An edit that changes a param: the behaviour is rebuilt, the run goes on.
    if [ "$rate" = 0.6 ]; then rate=0.65; else rate=0.6; fi
    sed -i -E "s/turn_rate: [0-9.]+/turn_rate: $rate/" "$config"
    edits=$((edits + 1))
    next_edit=$((next_edit + 10))
  fi
  sleep 1
done
status=0
wait "$run_pid" || status=$?
[ -n "$elapsed" ] || elapsed=$(($(date +%s) - started))
# The server closes the stream when the run ends: the client must have held it until then.
for _ in $(seq 1 50); do [ -s "$work/client_bytes" ] && break; sleep 0.1; done
client_bytes=$(cat "$work/client_bytes" 2>/dev/null || echo 0)
pids=()

fail=0
report() { echo "soak: $*"; }
[ "$client_bytes" -gt $((steps / 100)) ] ||
  { report "FAIL: the live client received only $client_bytes bytes"; fail=1; }
[ "$status" -eq 0 ] || { report "FAIL: exit status $status"; fail=1; }
if [ -s "$work/err.txt" ]; then
  report "FAIL: stderr is not empty:"
  head -20 "$work/err.txt"
  fail=1
fi
# Every step once, in order: the step records' numbers are 1..STEPS (the safe pass's record
# repeats the last); each reload wrote a header.
check=$(awk '
  /^\{"step": / { split($0, f, /[ ,]/); n = f[2] + 0
                  if (index($0, "\"safe\": true") > 0) { safe++; next }
                  if (n != expected + 1) bad++; expected = n; records++ }
  /^\{"arbiter_trace": 1, "reload": / { reloads++ }
  END { printf "%d %d %d %d %d", records, expected, bad, reloads, safe }' "$work/trace.jsonl")
read -r records last bad reloads safe <<<"$check"
[ "$records" -eq "$steps" ] && [ "$last" -eq "$steps" ] && [ "$bad" -eq 0 ] ||
  { report "FAIL: trace has $records step records, last $last, $bad out of order"; fail=1; }
# An edit in the last moments of the run may land after its last step.
[ "$reloads" -ge $((edits - 1)) ] || { report "FAIL: $edits edits, $reloads reloads"; fail=1; }
[ "$safe" -eq 1 ] || { report "FAIL: $safe safe passes at the end, want 1"; fail=1; }
trace_bytes=$(stat -c %s "$work/trace.jsonl")
# Resident memory after warm-up: samples past the first tenth of the steps.
read -r rss_min rss_max rss_n <<<"$(awk -v from=$((steps / 10)) '$2 >= from {
    if (n == 0 || $3 < lo) lo = $3; if ($3 > hi) hi = $3; n++ }
  END { printf "%d %d %d", lo, hi, n }' "$samples")"
rss_first=$(head -1 "$samples" | awk '{print $3}')
[ "$rss_n" -gt 0 ] && [ $((rss_max - rss_min)) -le 1024 ] ||
  { report "FAIL: resident memory after warm-up from $rss_min to $rss_max KiB ($rss_n samples)"; fail=1; }

report "$steps steps in ${elapsed} s ($((steps / (elapsed > 0 ? elapsed : 1))) steps/s), exit $status"
report "live client received $((client_bytes / 1048576)) MiB; $edits config edits, $reloads reloads"
report "trace: $records step records, $((trace_bytes / 1048576)) MiB, last step $last, $bad out of order, $safe safe pass"
report "resident memory: $rss_first KiB at the first sample; after warm-up $rss_min..$rss_max KiB" \
  "($((rss_max - rss_min)) KiB apart, $rss_n samples)"
[ "$fail" -eq 0 ] && report "passed" || report "FAILED"
exit "$fail"
