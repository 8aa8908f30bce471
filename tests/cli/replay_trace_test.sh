#!/bin/bash
# `arbiter replay --trace FILE` (and `--record FILE`) puts FILE in place once the replay has run:
# a replay that fails part way (here, on a recording damaged in its middle) leaves FILE as it
# was, and no partial file beside it; a file replaced keeps its mode. A symbolic link is written
# through and stays a link; a FIFO is written to, not replaced. An output that is the recording
# itself (or the config of `run`, or another input), or another output, is refused before
# anything is written.
set -eu
cli=$1
source_dir=$2
export ARBITER_PLUGIN_PATH=$3
config=$source_dir/tests/data/replay/counter.yaml
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"

"$cli" run "$config" --steps 3000 -q --record "$work/run.mcap" || fail "the run failed"
"$cli" replay "$work/run.mcap" --trace "$work/replay.jsonl" >"$work/out.txt" 2>"$work/err.txt" ||
  fail "the replay failed"
grep -q '"step": 3000' "$work/replay.jsonl" || fail "the replay's trace is not whole"

# 30000 bytes over the middle of the recording: whatever they hit past its first chunks (a
# chunk, its length), the replay fails there, after it has stepped.
size=$(stat -c %s "$work/run.mcap")
cp "$work/run.mcap" "$work/bad.mcap"
head -c 30000 /dev/zero | tr '\0' '\377' |
  dd of="$work/bad.mcap" bs=1 seek=$((size / 3)) conv=notrunc 2>/dev/null
echo previous >"$work/trace.jsonl"
echo previous >"$work/record.mcap"
expect_exit 1 "$cli" replay "$work/bad.mcap" --trace "$work/trace.jsonl" --record "$work/record.mcap"
grep -q "bad.mcap: error: at byte" "$work/err.txt" || fail "no error where the recording is damaged"
[[ $(cat "$work/trace.jsonl") == previous ]] || fail "the failed replay changed the trace file"
[[ $(cat "$work/record.mcap") == previous ]] || fail "the failed replay changed the recording file"
leftover=$(find "$work" -name '.*.arbiter-*')
[[ -z $leftover ]] || fail "a partial trace is left: $leftover"

# A file replaced keeps its mode; a new one gets the mode of any file created there.
echo previous >"$work/kept.jsonl"
echo previous >"$work/kept_record.mcap"
chmod 0640 "$work/kept.jsonl" "$work/kept_record.mcap"
(
  umask 022
  expect_exit 0 "$cli" replay "$work/run.mcap" --steps 5 --trace "$work/kept.jsonl" \
    --record "$work/kept_record.mcap"
  umask 077
  expect_exit 0 "$cli" replay "$work/run.mcap" --steps 5 --trace "$work/new.jsonl" \
    --record "$work/new.mcap"
)
[[ $(stat -c %a "$work/kept.jsonl") == 640 ]] || fail "the trace replaced lost its mode 0640"
[[ $(stat -c %a "$work/kept_record.mcap") == 640 ]] || fail "the recording replaced lost its mode"
grep -q '"step": 5' "$work/kept.jsonl" || fail "the trace was not replaced"
[[ $(stat -c %a "$work/new.jsonl") == 600 ]] || fail "a new trace is not 0666 less the umask"
[[ $(stat -c %a "$work/new.mcap") == 600 ]] || fail "a new recording is not 0666 less the umask"

# Through symbolic links: the files they lead to get the replay's outputs, the links stay links.
echo previous >"$work/real.jsonl"
ln -s real.jsonl "$work/link.jsonl"
mkdir "$work/records"
ln -s records/real.mcap "$work/link.mcap"  # to a file not there yet
expect_exit 0 "$cli" replay "$work/run.mcap" --steps 5 --trace "$work/link.jsonl" \
  --record "$work/link.mcap"
[[ -L $work/link.jsonl && -L $work/link.mcap ]] || fail "a link was replaced by a file"
grep -q '"step": 5' "$work/real.jsonl" || fail "the trace did not go where the link leads"
expect_exit 0 "$cli" replay "$work/records/real.mcap"
grep -q "replayed 5 steps" "$work/out.txt" || fail "the recording did not go where the link leads"

# A FIFO is written to: its reader gets the trace, and it is still a FIFO.
mkfifo "$work/fifo"
# Bounded: a FIFO renamed away leaves its reader waiting for a writer that never comes.
timeout 20 cat "$work/fifo" >"$work/from_fifo.jsonl" &
pids+=($!)
expect_exit 0 "$cli" replay "$work/run.mcap" --steps 5 --trace "$work/fifo"
wait "${pids[-1]}" || fail "the FIFO's reader got no trace"
[[ -p $work/fifo ]] || fail "the FIFO was replaced"
grep -q '"step": 5' "$work/from_fifo.jsonl" || fail "the FIFO's reader did not get the trace"
# So is a pipe named through a descriptor (/dev/fd/1, as /dev/stdout is).
"$cli" replay "$work/run.mcap" --steps 5 --trace /dev/fd/1 | cat >"$work/piped.jsonl"
[[ ${PIPESTATUS[0]} -eq 0 ]] || fail "the replay to /dev/fd/1 failed"
grep -q '"step": 5' "$work/piped.jsonl" || fail "the pipe did not get the trace"
leftover=$(find "$work" -name '.*.arbiter-*')
[[ -z $leftover ]] || fail "a partial file is left: $leftover"

# An output that is the recording (by its name, or through a link) is refused, and it is kept.
cp "$work/run.mcap" "$work/kept.mcap"
ln -s kept.mcap "$work/alias.mcap"
expect_exit 2 "$cli" replay "$work/kept.mcap" --record "$work/kept.mcap"
grep -qF "'$work/kept.mcap' is the recording being replayed ('$work/kept.mcap')" "$work/err.txt" ||
  fail "the refusal does not name the files"
expect_exit 2 "$cli" replay "$work/kept.mcap" --trace "$work/alias.mcap"
grep -qF "'$work/alias.mcap' is the recording being replayed ('$work/kept.mcap')" "$work/err.txt" ||
  fail "the refusal does not name the files"
cmp -s "$work/run.mcap" "$work/kept.mcap" || fail "the recording was written over"
# So is a run's output that is its config.
cp "$config" "$work/counter.yaml"
expect_exit 2 "$cli" run "$work/counter.yaml" --steps 5 --record "$work/counter.yaml"
grep -qF "'$work/counter.yaml' is the config being run" "$work/err.txt" || fail "no refusal"
expect_exit 2 "$cli" run "$work/counter.yaml" --steps 5 --trace "$work/./counter.yaml"
cmp -s "$config" "$work/counter.yaml" || fail "the config was written over"
# And one that is another of the command's inputs: a run's --inputs, a replay's --config.
echo kept >"$work/inputs.jsonl"
expect_exit 2 "$cli" run "$config" --steps 5 --inputs "$work/inputs.jsonl" \
  --trace "$work/inputs.jsonl"
grep -qF "'$work/inputs.jsonl' is the inputs being fed (--inputs)" "$work/err.txt" ||
  fail "no refusal of a run's output over its --inputs"
[[ $(cat "$work/inputs.jsonl") == kept ]] || fail "the inputs were written over"
expect_exit 2 "$cli" replay "$work/kept.mcap" --config "$work/counter.yaml" \
  --record "$work/counter.yaml"
grep -qF "'$work/counter.yaml' is the config replayed (--config)" "$work/err.txt" ||
  fail "no refusal of a replay's output over its --config"
cmp -s "$config" "$work/counter.yaml" || fail "the config was written over"

# An output that cannot be created is refused with the system's reason, before the replay runs.
expect_exit 2 "$cli" replay "$work/run.mcap" --record "$work/no_such_dir/x.mcap"
grep -qF "arbiter replay: cannot write '$work/no_such_dir/x.mcap': No such file or directory" \
  "$work/err.txt" || fail "no reason why the recording cannot be written"
expect_exit 2 "$cli" replay "$work/run.mcap" --trace "$work/no_such_dir/x.jsonl"
grep -qF "arbiter replay: cannot write '$work/no_such_dir/x.jsonl': No such file or directory" \
  "$work/err.txt" || fail "no reason why the trace cannot be written"
[[ ! -s $work/out.txt ]] || fail "the replay ran"
# So does a run's.
expect_exit 2 "$cli" run "$config" --steps 5 --record "$work/no_such_dir/x.mcap"
grep -qF "arbiter run: cannot write recording '$work/no_such_dir/x.mcap': No such file or" \
  "$work/err.txt" || fail "no reason why the run's recording cannot be written"
expect_exit 2 "$cli" run "$config" --steps 5 --trace "$work/no_such_dir/x.jsonl"
grep -qF "arbiter run: cannot write trace '$work/no_such_dir/x.jsonl': No such file or" \
  "$work/err.txt" || fail "no reason why the run's trace cannot be written"

# Two outputs that are one file (by name, or through a link) are refused, before anything runs.
echo kept >"$work/both.out"
ln -s both.out "$work/both_link.out"
expect_exit 2 "$cli" run "$config" --steps 5 --trace "$work/both.out" --record "$work/both.out"
grep -qF "arbiter run: --trace '$work/both.out' and --record '$work/both.out' are the same file" \
  "$work/err.txt" || fail "a run's --trace and --record on one file are not refused"
[[ ! -s $work/out.txt ]] || fail "the run ran"
expect_exit 2 "$cli" replay "$work/run.mcap" --trace "$work/both_link.out" \
  --record "$work/both.out"
grep -qF "arbiter replay: --trace '$work/both_link.out' and --record '$work/both.out' are the same" \
  "$work/err.txt" || fail "a replay's --trace and --record on one file are not refused"
[[ $(cat "$work/both.out") == kept ]] || fail "the file was written"
# A device keeps nothing to write over.
expect_exit 0 "$cli" replay "$work/run.mcap" --steps 5 --trace /dev/null --record /dev/null
echo ok
