#!/bin/bash
# An output named as standard output (/dev/stdout, or the file the shell sent it to) is written
# through it, whole, and alone: what the command says besides (its report, its summary) goes to
# standard error, so that the file holds a trace or a recording that reads back. One named as
# another descriptor the shell opened (/dev/fd/3) is written through it too.
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
# FILE holds "previous", then a whole recording of 30 steps that replays as recorded.
check_appended_recording() {  # WHAT FILE
  [[ $(head -c 9 "$2") == previous ]] || fail "$1: the file appended to was truncated"
  tail -c +10 "$2" >"$work/appended.mcap"
  expect_exit 0 "$cli" replay "$work/appended.mcap"
  grep -q "replayed 30 steps of .*: identical" "$work/out.txt" ||
    fail "$1: the recording appended does not replay"
}
# A recording appended to standard output's file keeps what was there, and follows it whole, from
# run and from replay.
for command in "run $config --steps 30" "replay $work/run.mcap"; do
  printf 'previous\n' >"$work/appended.bin"
  # shellcheck disable=SC2086  # the command's words
  "$cli" $command --record /dev/stdout >>"$work/appended.bin" 2>"$work/err.txt" ||
    fail "$command, recording appended to stdout, failed"
  check_appended_recording "$command --record /dev/stdout" "$work/appended.bin"
done

# An output named by another descriptor the shell opened (/dev/fd/N, /proc/self/fd/N, a link to
# one) is written through it, as standard output is: appended to when the shell appends (3>>FILE),
# from where the shell left it otherwise (3>FILE); never opened again, nor renamed over. Twice, to
# see the second run append to the first.
for command in "run $config --steps 30 -q" "replay $work/run.mcap"; do
  for name in /dev/fd/3 /proc/self/fd/3; do
    echo previous >"$work/fd.jsonl"
    for _ in 1 2; do
      # shellcheck disable=SC2086  # the command's words
      "$cli" $command --trace "$name" 3>>"$work/fd.jsonl" >"$work/out.txt" 2>"$work/err.txt" ||
        fail "$command --trace $name 3>>FILE failed"
    done
    [[ $(head -1 "$work/fd.jsonl") == previous ]] ||
      fail "$command --trace $name: the file appended to was truncated"
    [[ $(grep -c '^{"arbiter_trace": 1' "$work/fd.jsonl") == 2 ]] ||
      fail "$command --trace $name: the file does not hold both traces"
    tail -n +2 "$work/fd.jsonl" | head -31 >"$work/fd_first.jsonl"
    expect_exit 0 "$cli" diff "$work/fd_first.jsonl" "$work/direct.jsonl"
    grep -q "identical: 30 steps" "$work/out.txt" ||
      fail "$command --trace $name: the first trace appended is not whole"
  done
  printf 'previous\n' >"$work/fd.bin"
  # shellcheck disable=SC2086  # the command's words
  "$cli" $command --record /dev/fd/3 3>>"$work/fd.bin" >"$work/out.txt" 2>"$work/err.txt" ||
    fail "$command --record /dev/fd/3 3>>FILE failed"
  check_appended_recording "$command --record /dev/fd/3" "$work/fd.bin"
done
# Opened by the shell without appending, written from where the shell left it.
{
  echo previous >&3
  "$cli" run "$config" --steps 30 -q --trace /dev/fd/3 || fail "the run to 3>FILE failed"
} 3>"$work/fd.jsonl"
[[ $(head -1 "$work/fd.jsonl") == previous ]] ||
  fail "what the shell wrote to 3>FILE was written over"
tail -n +2 "$work/fd.jsonl" >"$work/fd_first.jsonl"
expect_exit 0 "$cli" diff "$work/fd_first.jsonl" "$work/direct.jsonl"
grep -q "identical: 30 steps" "$work/out.txt" || fail "the trace written to 3>FILE is not whole"
# Through a link to /dev/fd/3, which stays a link.
ln -s /dev/fd/3 "$work/fd_link"
echo previous >"$work/fd.jsonl"
"$cli" replay "$work/run.mcap" --trace "$work/fd_link" 3>>"$work/fd.jsonl" >/dev/null ||
  fail "the replay to a link to /dev/fd/3 failed"
[[ -L $work/fd_link && $(head -1 "$work/fd.jsonl") == previous ]] ||
  fail "the link to /dev/fd/3 was replaced, or its file truncated"
# A plot and a test's JUnit report too.
echo previous >"$work/fd.svg"
"$cli" plot "$work/direct.jsonl" -o /dev/fd/3 3>>"$work/fd.svg" || fail "the plot to 3>>FILE failed"
[[ $(head -1 "$work/fd.svg") == previous ]] ||
  fail "the file the plot was appended to was truncated"
grep -q '</svg>' "$work/fd.svg" || fail "the plot appended is not whole"
echo previous >"$work/fd.xml"
"$cli" test "$source_dir/tests/scenarios/paper/scripted_levels_by_step.test.yaml" \
  --junit /dev/fd/3 3>>"$work/fd.xml" >/dev/null || fail "the test with --junit 3>>FILE failed"
[[ $(head -1 "$work/fd.xml") == previous ]] ||
  fail "the file the JUnit report was appended to was truncated"
grep -q '</testsuites>' "$work/fd.xml" || fail "the JUnit report appended is not whole"
# test: the JUnit report alone on standard output, the test's report on stderr.
expect_exit 0 "$cli" test "$source_dir/tests/scenarios/paper/scripted_levels_by_step.test.yaml" \
  --junit /dev/stdout
[[ $(head -c 5 "$work/out.txt") == "<?xml" ]] || fail "the JUnit report on stdout is not XML alone"
grep -q '</testsuites>' "$work/out.txt" || fail "the JUnit report on stdout is not whole"
grep -q "^PASS " "$work/err.txt" || fail "the test's report is not on stderr"
grep -q "1 passed, 0 failed, 0 invalid" "$work/err.txt" || fail "the test's counts are not on stderr"
# Its colours follow where the report goes, as that is a terminal or not (a pty from script(1);
# skipped where there is none): the JUnit file on a terminal's stdout sends the report, plain, to
# a file on stderr; on a file's stdout, to the terminal on stderr, coloured.
if command -v script >/dev/null && script -qec true /dev/null >/dev/null 2>&1; then
  failing=$source_dir/tests/data/scenarios/failing/substituted_kick.test.yaml
  # shellcheck disable=SC2016  # expanded by the shell script(1) starts
  env -u NO_COLOR ARBITER_CLI="$cli" TEST="$failing" ERR="$work/report.txt" TERM=xterm script -qfec \
    '"$ARBITER_CLI" test "$TEST" --junit /dev/stdout 2>"$ERR"' /dev/null >/dev/null || true
  grep -q "^FAIL " "$work/report.txt" || fail "the report under a terminal's stdout is not on stderr"
  ! grep -q $'\e\\[' "$work/report.txt" || fail "the report to a file on stderr is coloured"
  # shellcheck disable=SC2016  # expanded by the shell script(1) starts
  env -u NO_COLOR ARBITER_CLI="$cli" TEST="$failing" XML="$work/report.xml" TERM=xterm script -qfec \
    '"$ARBITER_CLI" test "$TEST" --junit /dev/stdout >"$XML"' /dev/null >"$work/tty.txt" || true
  grep -q $'\e\\[' "$work/tty.txt" || fail "the report to a terminal on stderr is not coloured"
  [[ $(head -c 5 "$work/report.xml") == "<?xml" ]] || fail "the JUnit report on stdout is not XML"
fi
# A descriptor that is not open, or not for writing, is refused with why, before anything runs:
# never the file it was opened on, opened again.
expect_exit 2 "$cli" run "$config" --steps 5 --trace /dev/fd/9
grep -qx "arbiter run: cannot write trace '/dev/fd/9': Bad file descriptor" "$work/err.txt" ||
  fail "no reason why a closed descriptor cannot be written"
echo kept >"$work/read_only.txt"
expect_exit 2 "$cli" replay "$work/run.mcap" --record /dev/fd/3 3<"$work/read_only.txt"
grep -qx "arbiter replay: cannot write '/dev/fd/3': Bad file descriptor" "$work/err.txt" ||
  fail "no reason why a descriptor open for reading cannot be written"
[[ $(cat "$work/read_only.txt") == kept ]] || fail "the file open for reading was written"
echo ok
