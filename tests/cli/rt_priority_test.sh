#!/bin/bash
# `arbiter run --rt-priority N`: where the system permits SCHED_FIFO and locked memory the run
# proceeds as usual; where it does not (here: as an unprivileged user with no real-time limit),
# arbiter says what to grant (CAP_SYS_NICE, RLIMIT_RTPRIO, RLIMIT_MEMLOCK) and exits 2.
set -u
cli=$1
config=$2
out=$(mktemp) err=$(mktemp)
trap 'rm -f "$out" "$err"' EXIT
fail() { echo "FAIL: $*"; echo "--- stdout"; cat "$out"; echo "--- stderr"; cat "$err"; exit 1; }
passed=0

if chrt -f 1 true 2>/dev/null; then
  status=0
  "$cli" run "$config" --steps 20 --realtime --rt-priority 10 >"$out" 2>"$err" || status=$?
  [[ $status -eq 0 ]] || fail "exit status $status where SCHED_FIFO is permitted"
  passed=$((passed + 1))
fi

if [[ $(id -u) -eq 0 ]] && command -v setpriv >/dev/null; then
  status=0
  setpriv --reuid=65534 --regid=65534 --clear-groups --inh-caps=-all \
    prlimit --rtprio=0 "$cli" run "$config" --steps 5 --rt-priority 10 >"$out" 2>"$err" ||
    status=$?
  [[ $status -eq 2 ]] || fail "exit status $status without the privilege, want 2"
  for word in CAP_SYS_NICE RLIMIT_RTPRIO RLIMIT_MEMLOCK; do
    grep -q "$word" "$err" || fail "the error does not name $word"
  done
  grep -q '^arbiter run: --rt-priority 10: cannot run under SCHED_FIFO' "$err" ||
    fail "the error does not say what failed"
  passed=$((passed + 1))
elif ! chrt -f 1 true 2>/dev/null; then
  status=0
  "$cli" run "$config" --steps 5 --rt-priority 10 >"$out" 2>"$err" || status=$?
  [[ $status -eq 2 ]] || fail "exit status $status without the privilege, want 2"
  grep -q CAP_SYS_NICE "$err" || fail "the error does not name CAP_SYS_NICE"
  passed=$((passed + 1))
fi
echo "rt-priority: $passed passed, 0 failed"
