#!/usr/bin/env bash
# `arbiter plot`: the SVG timeline is well-formed XML with a row per behaviour, state machine and
# (with --actuators) actuator, marks the steps a behaviour is active, and a broken trace is
# reported as file:line:col.
#   plot_test.sh ARBITER SOURCE_DIR XMLLINT
set -euo pipefail
arbiter=$1
source=$2
xmllint=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*" >&2
  exit 1
}
count() {  # count XPATH FILE
  "$xmllint" --xpath "count($1)" "$2"
}
rows() {  # rows KIND FILE
  count "//*[local-name()='g'][@class='row $1']" "$2"
}

"$arbiter" run "$source/configs/paper/walk_and_kick.yaml" --steps 20 --trace "$work/paper.jsonl" -q
"$arbiter" plot "$work/paper.jsonl" -o "$work/paper.svg"
"$xmllint" --noout "$work/paper.svg" || fail "paper.svg is not well-formed"
[[ $(rows behaviour "$work/paper.svg") == 4 ]] || fail "expected 4 behaviour rows"
[[ $(rows controller "$work/paper.svg") == 0 ]] || fail "expected no state machine rows"
[[ $(rows actuator "$work/paper.svg") == 0 ]] || fail "actuator rows without --actuators"
# kick_ball requests 1 at steps 13 to 15 only: one active bar, two ticks (on, off).
kick="//*[local-name()='g'][@data-name='control/kick_ball']"
[[ $(count "$kick/*[@class='active']" "$work/paper.svg") == 1 ]] || fail "kick_ball: one active bar"
[[ $(count "$kick/*[@class='event']" "$work/paper.svg") == 2 ]] || fail "kick_ball: two ticks"
# Steps 1 to 20 share the 900 px wide plot: the active bar covers 3 of them.
width=$("$xmllint" --xpath "string($kick/*[@class='active']/@width)" "$work/paper.svg")
[[ $width == 135.0 ]] || fail "kick_ball's active bar is $width px wide, not 3 steps (135.0)"

"$arbiter" plot "$work/paper.jsonl" --actuators >"$work/actuators.svg"
"$xmllint" --noout "$work/actuators.svg" || fail "actuators.svg is not well-formed"
[[ $(rows actuator "$work/actuators.svg") == 3 ]] || fail "expected 3 actuator rows"

"$arbiter" run "$source/configs/paper/hierarchical.yaml" --steps 30 --trace "$work/h.jsonl" -q
"$arbiter" plot "$work/h.jsonl" -o "$work/h.svg"
"$xmllint" --noout "$work/h.svg" || fail "h.svg is not well-formed"
[[ $(rows controller "$work/h.svg") == 2 ]] || fail "expected 2 state machine rows"
[[ $(count "//*[local-name()='g'][@class='row controller']/*[@class='event']" "$work/h.svg") -gt 0 ]] ||
  fail "no state machine events marked"

# What behaviour code reports (the soccer world's kick and goal) is in the trace and marked on a row
# of its own; a trace without reports has no such row.
"$arbiter" run "$source/configs/soccer/walk_and_kick.yaml" --steps 220 --trace "$work/soccer.jsonl" -q
grep -q '"reported": \[{"by": "world", "text": "ball kicked"}\]' "$work/soccer.jsonl" ||
  fail "the trace does not record the kick"
"$arbiter" plot "$work/soccer.jsonl" -o "$work/soccer.svg"
"$xmllint" --noout "$work/soccer.svg" || fail "soccer.svg is not well-formed"
[[ $(rows reported "$work/soccer.svg") == 1 ]] || fail "expected one row of reported events"
reported="//*[local-name()='g'][@class='row reported']"
[[ $(count "$reported/*[@class='event']" "$work/soccer.svg") == 2 ]] ||
  fail "expected two reported events (kick, goal)"
[[ $("$xmllint" --xpath "string($reported/*[@class='event'][2]/*[local-name()='title'])" \
  "$work/soccer.svg") == "step 196: world: goal!" ]] || fail "the goal is not marked at step 196"
[[ $(rows reported "$work/paper.svg") == 0 ]] || fail "a row of reported events without any"

# A run whose config was reloaded (--watch): a reload header after step 2 that adds a behaviour.
{
  sed -n 1,3p "$work/paper.jsonl"
  head -n 1 "$work/paper.jsonl" |
    sed 's/"arbiter_trace": 1/&, "reload": 1, "after_step": 2/; s/"head_control"\]/"head_control", "look_around"]/'
  sed -n 4,6p "$work/paper.jsonl"
} >"$work/reloaded.jsonl"
"$arbiter" plot "$work/reloaded.jsonl" -o "$work/reloaded.svg"
"$xmllint" --noout "$work/reloaded.svg" || fail "reloaded.svg is not well-formed"
[[ $(rows behaviour "$work/reloaded.svg") == 5 ]] || fail "expected the 4 behaviours and the added one"
[[ $(count "//*[local-name()='line'][@class='reload']" "$work/reloaded.svg") == 1 ]] ||
  fail "expected one reload mark"
status=0
timeout 10 "$arbiter" view "$source/configs/paper/walk_and_kick.yaml" --trace "$work/reloaded.jsonl" \
  --serve 0 2>"$work/err" >/dev/null || status=$?
[[ $status == 1 ]] || fail "view of a reloaded run exits 1, not $status"
grep -q "reloaded.jsonl:4:1: error\[bad-trace\]: the config was reloaded during this run" "$work/err" ||
  fail "$(cat "$work/err")"

# A broken line is reported where it is, with the line and the place underlined.
head -n 3 "$work/paper.jsonl" >"$work/broken.jsonl"
echo '{"step": 3, "layers": {,}}' >>"$work/broken.jsonl"
status=0
"$arbiter" plot "$work/broken.jsonl" -o "$work/broken.svg" 2>"$work/err" || status=$?
[[ $status == 1 ]] || fail "a broken trace exits 1, not $status"
grep -q "^$work/broken.jsonl:4:24: error\[bad-trace\]: not JSON: " "$work/err" || fail "$(cat "$work/err")"
grep -qx '4 | {"step": 3, "layers": {,}}' "$work/err" || fail "no source line: $(cat "$work/err")"
grep -qx '  |                        ^' "$work/err" || fail "no underline: $(cat "$work/err")"
[[ ! -e $work/broken.svg ]] || fail "no SVG for a broken trace"

# A JSON object that is not a trace header.
echo '{"arbiter": 1, "name": "walk_and_kick"}' >"$work/config.json"
status=0
"$arbiter" plot "$work/config.json" 2>"$work/err" >/dev/null || status=$?
[[ $status == 1 ]] || fail "a config given as trace exits 1, not $status"
grep -q "config.json:1:1: error\[bad-trace\]: a trace starts with a header" "$work/err" || fail "$(cat "$work/err")"
echo "plot ok"
