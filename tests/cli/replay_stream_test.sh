#!/bin/bash
# Recordings are read as the tools go, never whole: a long recording replays and diffs in bounded
# memory, and `replay --steps N` reads only the chunks it needs. The end of a recording (MCAP's
# summary, footer, CRCs and closing magic) is checked: a damaged end is a warning in every tool,
# which still reads the steps; a recording cut off before its trace header gets one message from
# every tool.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
config=$source_dir/tests/data/replay/counter.yaml
steps=40000
# What replay and diff hold does not grow with the recording: about 20 MiB, for any length (a
# whole read held 88 MiB for replay, 52 MiB for diff, 53 MiB for diff with the trace).
limit_kb=40960
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
# Runs COMMAND... as expect_exit 0 does, and sets `peak_kb` to its peak resident memory
# (VmHWM, read until it exits: it only grows).
peak_kb=0
measure() {
  "$@" >"$work/out.txt" 2>"$work/err.txt" &
  pid=$!
  peak_kb=0
  while kill -0 "$pid" 2>/dev/null; do
    local hwm
    hwm=$(awk '/^VmHWM:/ {print $2}' "/proc/$pid/status" 2>/dev/null || true)
    [[ -n $hwm && $hwm -gt $peak_kb ]] && peak_kb=$hwm
    sleep 0.05
  done
  wait "$pid" || fail "exit $?: $*"
  pid=
}
# AddressSanitizer's shadow memory and quarantine say nothing of what the tools hold.
sanitized=0
grep -qa __asan_init "$cli" && sanitized=1

expect_exit 0 "$cli" run "$config" --steps $steps -q --record "$work/long.mcap" \
  --trace "$work/long.jsonl"

measure "$cli" replay "$work/long.mcap"
grep -qx "replayed $steps steps of $work/long.mcap: identical to the recording" "$work/out.txt" ||
  fail "the long recording does not replay"
echo "replay: peak $peak_kb KB"
[[ $sanitized -eq 1 || $peak_kb -le $limit_kb ]] ||
  fail "replay of $steps steps held $peak_kb KB; at most $limit_kb KB"

measure "$cli" diff "$work/long.mcap" "$work/long.mcap"
grep -q "identical: $steps steps" "$work/out.txt" || fail "diff of the long recording"
echo "diff: peak $peak_kb KB"
[[ $sanitized -eq 1 || $peak_kb -le $limit_kb ]] ||
  fail "diff of $steps steps held $peak_kb KB; at most $limit_kb KB"

measure "$cli" diff "$work/long.jsonl" "$work/long.mcap"
grep -q "identical: $steps steps" "$work/out.txt" || fail "diff of the long trace and recording"
echo "diff of the trace: peak $peak_kb KB"
[[ $sanitized -eq 1 || $peak_kb -le $limit_kb ]] ||
  fail "diff of a $steps-step trace held $peak_kb KB; at most $limit_kb KB"

# Only the first chunks: replay --steps 10 never reads as far as the cut, so it has nothing to say.
head -c 200000 "$work/long.mcap" >"$work/head.mcap"
expect_exit 0 "$cli" replay "$work/head.mcap" --steps 10
grep -qx "replayed 10 steps of $work/head.mcap: identical to the recording" "$work/out.txt" ||
  fail "replay --steps 10 of the first chunks"
[[ ! -s "$work/err.txt" ]] || fail "replay --steps 10 read past what it needs"

# Without its closing magic: every tool warns, and reads the steps.
expect_exit 0 "$cli" run "$config" --steps 30 -q --record "$work/short.mcap"
head -c -8 "$work/short.mcap" >"$work/no_magic.mcap"
damaged="no_magic.mcap: warning: the end of the recording is not whole: at byte [0-9]*: the file does not end with MCAP's magic bytes after its footer"
expect_exit 0 "$cli" replay "$work/no_magic.mcap"
grep -q "identical to the recording" "$work/out.txt" || fail "replay without the magic"
grep -q "$damaged" "$work/err.txt" || fail "replay does not warn of the missing magic"
expect_exit 0 "$cli" diff "$work/no_magic.mcap" "$work/short.mcap"
grep -q "identical: 30 steps" "$work/out.txt" || fail "diff without the magic"
grep -q "$damaged" "$work/err.txt" || fail "diff does not warn of the missing magic"
expect_exit 0 "$cli" plot "$work/no_magic.mcap" -o "$work/no_magic.svg"
grep -q "$damaged" "$work/err.txt" || fail "plot does not warn of the missing magic"
[[ -s "$work/no_magic.svg" ]] || fail "plot without the magic"
# view serves until stopped: wait for its warning, then stop it.
serve_until "$damaged" "$cli" view "$config" --trace "$work/no_magic.mcap" --serve 0
grep -q "$damaged" "$work/err.txt" || fail "view does not warn of the missing magic"

# Cut off before its trace header: one message, whichever tool reads it.
head -c 100 "$work/short.mcap" >"$work/cut.mcap"
cut="cut.mcap: error.*: the recording was cut off while it was written, before its trace header: it holds no step (it is whole up to byte [0-9]*)"
expect_exit 1 "$cli" replay "$work/cut.mcap"
grep -q "$cut" "$work/err.txt" || fail "replay of a recording cut before its header"
expect_exit 2 "$cli" diff "$work/cut.mcap" "$work/short.mcap"
grep -q "$cut" "$work/err.txt" || fail "diff of a recording cut before its header"
expect_exit 1 "$cli" plot "$work/cut.mcap" -o "$work/cut.svg"
grep -q "$cut" "$work/err.txt" || fail "plot of a recording cut before its header"
expect_exit 1 "$cli" view "$config" --trace "$work/cut.mcap" --serve 0
grep -q "$cut" "$work/err.txt" || fail "view of a recording cut before its header"
echo ok
