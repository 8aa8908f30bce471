#!/bin/bash
# `arbiter run --rt-priority N`: where the system permits SCHED_FIFO and locked memory the run
# proceeds as usual; where it does not (here: as an unprivileged user with no real-time limit),
# arbiter says what to grant (CAP_SYS_NICE, RLIMIT_RTPRIO, RLIMIT_MEMLOCK) and exits 2.
set -eu
cli=$1
config=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
err=$work/err.txt
passed=0

if chrt -f 1 true 2>/dev/null; then
  expect_exit 0 "$cli" run "$config" --steps 20 --realtime --rt-priority 10
  passed=$((passed + 1))
fi

if [[ $(id -u) -eq 0 ]] && command -v setpriv >/dev/null; then
  expect_exit 2 setpriv --reuid=65534 --regid=65534 --clear-groups --inh-caps=-all \
    prlimit --rtprio=0 "$cli" run "$config" --steps 5 --rt-priority 10
  for word in CAP_SYS_NICE RLIMIT_RTPRIO RLIMIT_MEMLOCK; do
    grep -q "$word" "$err" || fail "the error does not name $word"
  done
  grep -q '^arbiter run: --rt-priority 10: cannot run under SCHED_FIFO' "$err" ||
    fail "the error does not say what failed"
  passed=$((passed + 1))
elif ! chrt -f 1 true 2>/dev/null; then
  expect_exit 2 "$cli" run "$config" --steps 5 --rt-priority 10
  grep -q CAP_SYS_NICE "$err" || fail "the error does not name CAP_SYS_NICE"
  passed=$((passed + 1))
fi
echo "rt-priority: $passed passed, 0 failed"
