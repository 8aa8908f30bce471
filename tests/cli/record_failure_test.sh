#!/bin/bash
# A recording that cannot be written, and one whose run is killed, from the outside:
# - a full disk (/dev/full) and a file size limit (ulimit -f): the run goes on, the failure is
#   reported at once on stderr (the file and the error), the exit status is non-zero, and what
#   was written before is still read by replay and diff;
# - replay --record to a destination that fails, likewise;
# - a paced run killed with SIGKILL keeps all its steps but about the last second.
set -eu
cli=$1
source_dir=$2
soccer=$source_dir/configs/soccer/walk_and_kick.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
# The step a recording ends after, from replay's warning that it was cut off.
cut_after() {
  sed -nE 's/.*: warning: the recording was cut off while it was written: it ends after step ([0-9]+) .*/\1/p' \
    "$work/err.txt"
}

# A state machine that prints a line at every step: the run's stdout tells how far it got.
cat >"$work/ticking.yaml" <<'EOF'
arbiter: 1
name: ticking
rate_hz: 20
state_machines:
  clock:
    states:
      tick: {type: scripted, params: {append: [tick]}}
    queue: [tick]
EOF

# A full disk, paced: reported while the run goes on, which then runs every step and exits 1.
"$cli" run "$work/ticking.yaml" --realtime --steps 80 --record /dev/full \
  >"$work/full_out.txt" 2>"$work/full_err.txt" &
pid=$!
for _ in $(seq 300); do
  grep -q "No space left on device" "$work/full_err.txt" && break
  sleep 0.01
done
kill -0 "$pid" 2>/dev/null || fail "the write to /dev/full was not reported while the run went on"
grep -qx "error: recording '/dev/full': a write failed: No space left on device (at the start); the run goes on unrecorded, the file keeps what was written before" \
  "$work/full_err.txt" || fail "the failed write is not reported at once"
set +e
wait "$pid"
code=$?
set -e
pid=
[[ $code -eq 1 ]] || fail "a run whose recording failed exits $code, not 1"
grep -q "^step   80  clock: tick (cycle 80" "$work/full_out.txt" || fail "the run did not go on"
grep -qx "arbiter run: writing recording '/dev/full' failed: No space left on device (at the start); it holds the steps written before" \
  "$work/full_err.txt" || fail "the end of the run does not say the recording failed"

# A file size limit (100 KiB) reached while the run steps flat out.
expect_exit 1 bash -c "ulimit -f 100 && exec \"\$0\" run \"\$1\" --steps 3000 --record \"\$2\"" \
  "$cli" "$soccer" "$work/big.mcap"
grep -q "^3000 steps\.$" "$work/out.txt" || fail "the run did not go on past the size limit"
grep -qE "^error: recording '$work/big.mcap': a write failed: File too large \(writing step [0-9]+\)" \
  "$work/err.txt" || fail "the size limit is not reported at once"
grep -qE "^arbiter run: writing recording '$work/big.mcap' failed: File too large" \
  "$work/err.txt" || fail "the end of the run does not say the recording failed"
[[ $(stat -c %s "$work/big.mcap") -le 102400 ]] || fail "the recording grew past the limit"
expect_exit 0 "$cli" replay "$work/big.mcap"
kept=$(cut_after)
[[ -n $kept && $kept -gt 100 ]] || fail "the recording does not keep what was written before"
grep -qx "replayed $kept steps of $work/big.mcap: identical to the recording" "$work/out.txt" ||
  fail "the steps written before the failure do not replay"
expect_exit 0 "$cli" diff "$work/big.mcap" "$work/big.mcap"
grep -q "identical: $kept steps" "$work/out.txt" || fail "diff of the cut recording"

# replay --record: the replay's verdict, then the failure, and exit 2.
expect_exit 0 "$cli" run "$soccer" --steps 3000 -q --record "$work/run.mcap"
expect_exit 2 "$cli" replay "$work/run.mcap" --record /dev/full
grep -qx "replayed 3000 steps of $work/run.mcap: identical to the recording" "$work/out.txt" ||
  fail "replay did not go on past the failed recording"
grep -qx "arbiter replay: writing recording '/dev/full' failed: No space left on device (at the start); it holds the steps written before" \
  "$work/err.txt" || fail "replay does not say its recording failed"
expect_exit 2 bash -c "ulimit -f 100 && exec \"\$0\" replay \"\$1\" --record \"\$2\"" \
  "$cli" "$work/run.mcap" "$work/replayed.mcap"
grep -qE "^error: recording '$work/replayed.mcap': a write failed: File too large" \
  "$work/err.txt" || fail "the replay's size limit is not reported at once"
expect_exit 0 "$cli" replay "$work/replayed.mcap"
kept=$(cut_after)
[[ -n $kept && $kept -gt 100 ]] || fail "the replay's recording does not keep what was written before"
grep -qx "replayed $kept steps of $work/replayed.mcap: identical to the recording" "$work/out.txt" ||
  fail "the replay's steps written before the failure do not replay"

# Killed 3 s into a paced run: the steps before the last second or so are in the recording.
"$cli" run "$work/ticking.yaml" --realtime --steps 100000 --record "$work/killed.mcap" \
  >"$work/killed_out.txt" 2>&1 &
pid=$!
for _ in $(seq 600); do  # up to 30 s on a busy machine
  grep -q "^step    1 " "$work/killed_out.txt" && break
  sleep 0.05
done
sleep 3
kill -9 "$pid"
wait "$pid" 2>/dev/null || true
pid=
ran=$(sed -nE 's/^step +([0-9]+) .*/\1/p' "$work/killed_out.txt" | tail -1)
expect_exit 0 "$cli" replay "$work/killed.mcap"
kept=$(cut_after)
# 1.5 s at 20 Hz: the flush interval and the writer's period, with room for a busy machine.
[[ -n $kept && $kept -ge $((ran - 30)) ]] ||
  fail "a run killed after step $ran keeps its steps up to ${kept:-none}"
echo ok
