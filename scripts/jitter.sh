#!/usr/bin/env bash
# Period jitter of `arbiter run --realtime` (docs/performance.md): the soccer demo paced at 100 Hz
# and at 1 kHz, with normal scheduling and, where the system permits it, with --rt-priority.
# Prints one table row per run from the run's summary.
#
#   scripts/jitter.sh [BUILD_DIR] [SECONDS]     # BUILD_DIR defaults to build/dev; 20 s per run
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
build=${1:-build/dev}
seconds=${2:-20}
cli=$build/cli/arbiter
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

echo "| rate | scheduling | steps | jitter p50 | jitter p99 | jitter max | step p50 | step p99 | step max | overruns (periods missed) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for rate in 100 1000; do
  sed -E "s/^rate_hz: .*/rate_hz: $rate/" configs/soccer/walk_and_kick.yaml >"$work/demo_$rate.yaml"
  for rt in "" 50; do
    args=()
    label=normal
    if [ -n "$rt" ]; then
      chrt -f 1 true 2>/dev/null || { echo "| $rate Hz | SCHED_FIFO $rt | not permitted here |"; continue; }
      args=(--rt-priority "$rt")
      label="SCHED_FIFO $rt"
    fi
    steps=$((rate * seconds))
    "$cli" run "$work/demo_$rate.yaml" --plugin-path "$build/plugins" --realtime --steps "$steps" \
      "${args[@]}" >"$work/out.txt"
    duration=$(sed -nE 's/^step duration: p50 (.*) µs, p99 (.*) µs, max (.*) µs .*/\1 µs | \2 µs | \3 µs/p' "$work/out.txt")
    jitter=$(sed -nE 's/^period jitter .*: p50 (.*) µs, p99 (.*) µs, max (.*) µs; ([0-9]+) overruns?, ([0-9]+) periods? missed/\1 µs | \2 µs | \3 µs/p' "$work/out.txt")
    overruns=$(sed -nE 's/^period jitter .*; ([0-9]+) overruns?, ([0-9]+) periods? missed/\1 (\2)/p' "$work/out.txt")
    echo "| $rate Hz | $label | $steps | $jitter | $duration | $overruns |"
  done
done
