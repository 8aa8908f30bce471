#!/bin/bash
# `arbiter run --watch --realtime`: a behaviour that a reload removes and a later one adds back
# is one behaviour to the summary, listed once with every step it was active in, before and after
# (as many as the trace shows), not once more as removed.
set -eu
cli=$1
config=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cp "$config" "$work/robot.yaml"
cp "$config" "$work/original.yaml"

"$cli" run "$work/robot.yaml" --watch --realtime --trace "$work/trace.jsonl" \
  >"$work/out.txt" 2>"$work/err.txt" &
pid=$!

wait_for 'control/head_control activated' "$work/out.txt"
sed -i '/^      head_control:/,/^          writes: {head_angle: -0.5}/d; /-> head_control/d' \
  "$work/robot.yaml"
wait_for '^  - behaviour control/head_control (scripted)$' "$work/out.txt"
wait_for 'reloaded walk_and_kick: 1 layers, 3 behaviours' "$work/out.txt"
sleep 0.3  # a few steps without it
cp "$work/original.yaml" "$work/robot.yaml"
wait_for '^  + behaviour control/head_control (scripted)$' "$work/out.txt"
wait_for 'reloaded walk_and_kick: 1 layers, 4 behaviours' "$work/out.txt"
wait_for 'control/head_control activated' <(sed -n '/1 layers, 4 behaviours/,$p' "$work/out.txt")
kill -INT "$pid"
status=0
wait "$pid" || status=$?
pid=
[ "$status" -eq 0 ] || fail "exit status $status after SIGINT"

summary=$(sed -n '/^Active steps per behaviour:$/,/^interrupted: /p' "$work/out.txt")
[ -n "$summary" ] || fail "no summary of behaviours"
[ "$(grep -c '^  control/head_control ' <<<"$summary")" -eq 1 ] ||
  fail "control/head_control is not listed once: $summary"
! grep -q 'removed by a reload' <<<"$summary" || fail "a behaviour back in the config listed as removed"
# Each behaviour's active steps are the steps the trace has it active in, across the reloads.
for behaviour in kick_ball go_behind_ball search_for_ball head_control; do
  traced=$(grep -c "\"$behaviour\": {[^}]*\"active\": true" "$work/trace.jsonl" || true)
  listed=$(sed -nE "s|^  control/$behaviour +([0-9]+)  \(final activation .*\)$|\1|p" <<<"$summary")
  [ "$listed" = "$traced" ] || fail "control/$behaviour: $listed active steps listed, $traced traced"
done
echo "a behaviour removed and added back: listed once, its active steps as traced"
