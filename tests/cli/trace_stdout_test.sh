#!/bin/bash
# An output named as standard output (/dev/stdout, or the file the shell sent it to) is written
# through it, whole, and alone: what the command says besides (its report, its summary) goes to
# standard error, so that the file holds a trace or a recording that reads back.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
config=$source_dir/tests/data/replay/counter.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$config" --steps 30 -q --trace "$work/direct.jsonl" --record "$work/run.mcap" ||
  fail "the run failed"

# run: the trace, whole, with the run's report on stderr.
expect_exit 0 "$cli" run "$config" --steps 30 --trace /dev/stdout
grep -q '^{"arbiter_trace": 1' <(head -1 "$work/out.txt") || fail "the trace's header is not first"
grep -q "simulated 3.00 s" "$work/err.txt" || fail "the run's summary is not on stderr"
grep -qv '^{' "$work/out.txt" && fail "the trace holds a line that is not a record"
cp "$work/out.txt" "$work/stdout.jsonl"
expect_exit 0 "$cli" diff "$work/stdout.jsonl" "$work/direct.jsonl"
grep -q "identical: 30 steps" "$work/out.txt" || fail "the trace on stdout is not the run's"
# The file the shell opened, by its own name, is written through standard output too.
# shellcheck disable=SC2094  # one file, as the output and as stdout, is what is tested
"$cli" run "$config" --steps 30 --trace "$work/same.jsonl" >"$work/same.jsonl" 2>"$work/err.txt" ||
  fail "the run to its own stdout failed"
expect_exit 0 "$cli" diff "$work/same.jsonl" "$work/direct.jsonl"
grep -q "identical: 30 steps" "$work/out.txt" || fail "the trace on the stdout file is not whole"
# Appended to, as the shell opened it: what was there is kept.
echo previous >"$work/appended.txt"
"$cli" run "$config" --steps 30 -q --trace /dev/stdout >>"$work/appended.txt" ||
  fail "the appending run failed"
[[ $(head -1 "$work/appended.txt") == previous ]] || fail "the file appended to was truncated"
grep -q '"step": 30' "$work/appended.txt" || fail "the appended trace is not whole"

# replay: the trace and the recording, with the verdict on stderr.
expect_exit 0 "$cli" replay "$work/run.mcap" --trace /dev/stdout
grep -q "identical to the recording" "$work/err.txt" || fail "the verdict is not on stderr"
cp "$work/out.txt" "$work/replay.jsonl"
expect_exit 0 "$cli" diff "$work/replay.jsonl" "$work/direct.jsonl"
grep -q "identical: 30 steps" "$work/out.txt" || fail "the replay's trace on stdout is not whole"
"$cli" replay "$work/run.mcap" --record /dev/stdout >"$work/replay.mcap" 2>"$work/err.txt" ||
  fail "the replay recorded to stdout failed"
expect_exit 0 "$cli" replay "$work/replay.mcap"
grep -q "replayed 30 steps of .*: identical" "$work/out.txt" ||
  fail "the recording written to stdout does not replay"
# So does a run's recording.
"$cli" run "$config" --steps 30 --record /dev/stdout >"$work/run2.mcap" 2>"$work/err.txt" ||
  fail "the run recorded to stdout failed"
grep -q "simulated 3.00 s" "$work/err.txt" || fail "the run's summary is not on stderr"
expect_exit 0 "$cli" replay "$work/run2.mcap"
grep -q "replayed 30 steps of .*: identical" "$work/out.txt" ||
  fail "the run's recording written to stdout does not replay"
# A recording appended to standard output's file keeps what was there, and follows it whole, from
# run and from replay.
for command in "run $config --steps 30" "replay $work/run.mcap"; do
  printf 'previous\n' >"$work/appended.bin"
  # shellcheck disable=SC2086  # the command's words
  "$cli" $command --record /dev/stdout >>"$work/appended.bin" 2>"$work/err.txt" ||
    fail "$command, recording appended to stdout, failed"
  [[ $(head -c 9 "$work/appended.bin") == previous ]] ||
    fail "$command: the file appended to was truncated"
  tail -c +10 "$work/appended.bin" >"$work/appended.mcap"
  expect_exit 0 "$cli" replay "$work/appended.mcap"
  grep -q "replayed 30 steps of .*: identical" "$work/out.txt" ||
    fail "$command: the recording appended to stdout does not replay"
done
echo ok
