#!/bin/bash
# `arbiter run --watch --realtime` and the summary of behaviours: one that a reload removes and a
# later one adds back is one behaviour to it, listed once with every step it was active in,
# before and after (as many as the trace shows), not once more as removed; those removed by a
# reload that leaves none are still listed.
set -eu
cli=$1
config=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cp "$config" "$work/original.yaml"
# Every edit is a file renamed over the config: the watcher never reads one half written.
sed '/^    behaviours:/,$d' "$config" >"$work/none.yaml"
echo '    behaviours: {}' >>"$work/none.yaml"

# start: a watched run of a fresh copy of the config, once a behaviour is active.
start() {
  cp "$work/original.yaml" "$work/robot.yaml"
  # Emptied first: the last run's lines must not pass for this one's.
  : >"$work/out.txt"
  "$cli" run "$work/robot.yaml" --watch --realtime --trace "$work/trace.jsonl" \
    >"$work/out.txt" 2>"$work/err.txt" &
  pid=$!
  wait_for 'control/head_control activated' "$work/out.txt"
}
# stop: ends the run as Ctrl-C does, and keeps its summary of behaviours in `summary`.
stop() {
  kill -INT "$pid"
  local status=0
  wait "$pid" || status=$?
  pid=
  [ "$status" -eq 0 ] || fail "exit status $status after SIGINT"
  summary=$(sed -n '/^Active steps per behaviour:$/,/^interrupted: /p' "$work/out.txt")
  [ -n "$summary" ] || fail "no summary of behaviours"
}
# listed_as_traced END: each behaviour is listed once, its line ending in END, with as many active
# steps as the trace has it active in, across the reloads.
listed_as_traced() {
  local behaviour traced listed
  for behaviour in kick_ball go_behind_ball search_for_ball head_control; do
    [ "$(grep -c "^  control/$behaviour " <<<"$summary")" -eq 1 ] ||
      fail "control/$behaviour is not listed once: $summary"
    traced=$(grep -c "\"$behaviour\": {[^}]*\"active\": true" "$work/trace.jsonl" || true)
    listed=$(sed -nE "s|^  control/$behaviour +([0-9]+)  $1$|\\1|p" <<<"$summary")
    [ "$listed" = "$traced" ] || fail "control/$behaviour: '$listed' active steps listed, $traced traced"
  done
}

start
sed -i '/^      head_control:/,/^          writes: {head_angle: -0.5}/d; /-> head_control/d' \
  "$work/robot.yaml"
wait_for '^  - behaviour control/head_control (scripted)$' "$work/out.txt"
wait_for 'reloaded walk_and_kick: 1 layers, 3 behaviours' "$work/out.txt"
sleep 0.3  # a few steps without it
cp "$work/original.yaml" "$work/new.yaml"
mv "$work/new.yaml" "$work/robot.yaml"
wait_for '^  + behaviour control/head_control (scripted)$' "$work/out.txt"
wait_for 'reloaded walk_and_kick: 1 layers, 4 behaviours' "$work/out.txt"
wait_for 'control/head_control activated' <(sed -n '/1 layers, 4 behaviours/,$p' "$work/out.txt")
stop
! grep -q 'removed by a reload' <<<"$summary" || fail "a behaviour back in the config listed as removed"
listed_as_traced '\(final activation .*\)'

start
mv "$work/none.yaml" "$work/robot.yaml"
wait_for 'reloaded walk_and_kick: 1 layers, 0 behaviours' "$work/out.txt"
stop
listed_as_traced '\(removed by a reload\)'
echo "a behaviour removed and added back: listed once, its active steps as traced; all removed: listed"
