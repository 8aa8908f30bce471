#!/bin/bash
# Records the soccer demo for the recording-based scenario tests: OUT gets the test files of
# tests/scenarios/recorded and tests/data/scenarios/recorded and the demo config at their places
# in the source tree, so that their relative paths hold, and beside the test files the recording
# (walk_and_kick.mcap), the trace of the same run (walk_and_kick.jsonl) and a recording cut off
# before its first chunk (cut.mcap).
set -eu
cli=$1
source_dir=$2
out=$3
rm -rf "$out"
mkdir -p "$out/configs/soccer" "$out/tests/scenarios" "$out/tests/data/scenarios"
cp "$source_dir/configs/soccer/walk_and_kick.yaml" "$out/configs/soccer/"
cp -r "$source_dir/tests/scenarios/recorded" "$out/tests/scenarios/"
cp -r "$source_dir/tests/data/scenarios/recorded" "$out/tests/data/scenarios/"
run=$out/tests/scenarios/recorded
"$cli" run "$out/configs/soccer/walk_and_kick.yaml" --steps 180 -q \
  --record "$run/walk_and_kick.mcap" --trace "$run/walk_and_kick.jsonl"
cp "$run/walk_and_kick.mcap" "$run/walk_and_kick.jsonl" "$out/tests/data/scenarios/recorded/"
head -c 2000 "$run/walk_and_kick.mcap" >"$out/tests/data/scenarios/recorded/cut.mcap"
