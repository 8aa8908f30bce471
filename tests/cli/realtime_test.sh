#!/bin/bash
# `arbiter run --realtime` keeps absolute deadlines: at a rate no step can keep (50 kHz), steps
# overrun, each is counted with the periods it skipped, and the next step waits for the next period
# boundary instead of following at once; every step still runs and carries "t" and "duration".
set -u
cli=$1
config=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

sed -E 's/^rate_hz: .*/rate_hz: 50000/' "$config" >"$work/fast.yaml"
grep -q '^rate_hz: 50000' "$work/fast.yaml" || fail "the config has no rate_hz line"
"$cli" run "$work/fast.yaml" --realtime --steps 2000 --trace "$work/trace.jsonl" >"$work/out.txt" ||
  fail "exit status $?"
line=$(grep '^period jitter' "$work/out.txt") || fail "no jitter line in the summary"
overruns=$(sed -nE 's/.*; ([0-9]+) overruns?, ([0-9]+) periods? missed$/\1/p' <<<"$line")
missed=$(sed -nE 's/.*; ([0-9]+) overruns?, ([0-9]+) periods? missed$/\2/p' <<<"$line")
[[ -n $overruns && $overruns -gt 0 ]] || fail "no overrun counted at 50 kHz: $line"
[[ $missed -ge $overruns ]] || fail "fewer periods missed than overruns: $line"
grep -q '^step duration: p50 .* (2000 steps)$' "$work/out.txt" || fail "no step duration line"
# Every step ran once, with its time: step i+1 starts after step i started.
awk '/^\{"step": / && !/"safe": true/ {
    match($0, /"t": [0-9.e-]+/); t = substr($0, RSTART + 5, RLENGTH - 5) + 0
    if (!/"duration": [0-9.e-]+/) bad++
    if (n > 0 && t <= last) bad++
    last = t; n++ }
  END { if (n != 2000 || bad) { print n " steps, " bad " bad"; exit 1 } }' "$work/trace.jsonl" ||
  fail "the trace does not time every step once"
echo "realtime: 1 passed, 0 failed"
