#!/bin/bash
# `arbiter run --serve --edit --trace`: an edit made and saved through the studio's API (the
# requests its page sends) is reloaded into the running engine, and the trace shows it where it
# happened: the reload's header between the last step of the old program and the first of the
# new, at the step the terminal names, the edited behaviour's new level from that step on, and a
# state machine the edit did not touch carrying on from its cycle and state, not started again.
set -eu
cli=$1
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cat >"$work/robot.yaml" <<'YAML'
arbiter: 1
name: carried
rate_hz: 50
layers:
  - name: main
    behaviours:
      ticker: {type: scripted, params: {activation: 1}}
      plan: {type: state_machine, params: {machine: plan}}
state_machines:
  plan:
    states:
      first: {type: scripted, params: {hold: 2}}
      second: {type: scripted, params: {hold: 100000}}
    queue: [first, second]
YAML

"$cli" run "$work/robot.yaml" --serve 127.0.0.1:0 --edit --trace "$work/trace.jsonl" \
  >"$work/out.txt" 2>"$work/err.txt" &
pid=$!
url=$(printed 's|^serving the studio at (http://127\.0\.0\.1:[0-9]+/\?token=[0-9a-f]+)$|\1|p' \
  "$work/out.txt")
[ -n "$url" ] || fail "no studio address printed"
origin=${url%%/\?*}
token=${url##*token=}
post() {  # PATH BODY-FILE: the page's request, with its token and origin
  curl -sf -H "X-Arbiter-Token: $token" -H "Origin: $origin" -H 'Content-Type: application/json' \
    --data-binary "@$2" "$origin$1"
}
value() {  # FILE KEY...: the JSON value under the keys (a string as it is, else as JSON)
  python3 -c 'import json, sys
v = json.load(open(sys.argv[1]))
for key in sys.argv[2:]: v = v[key]
print(v if isinstance(v, str) else json.dumps(v))' "$@"
}
# Some steps in, so that the machine has a cycle and a state of its own to keep.
wait_for '"step": 20,' "$work/trace.jsonl"

echo '{"op": "set_param", "layer": "main", "behaviour": "ticker", "param": "activation",
       "value": 0.5}' >"$work/op.json"
post /studio/edit "$work/op.json" >"$work/edit.json" || fail "the edit was refused"
python3 -c 'import json, sys
files = json.load(open(sys.argv[1]))["files"]
print(json.dumps({"files": [{k: f[k] for k in ("path", "text", "base")} for f in files]}))' \
  "$work/edit.json" >"$work/save.json"
post /studio/save "$work/save.json" >"$work/saved.json" || fail "the save was refused"
[ "$(value "$work/saved.json" applied staged)" = true ] || fail "the save was not staged"
wait_for '^step *[0-9]*  reloaded carried' "$work/out.txt"
sleep 0.2  # a few steps of the reloaded program
kill -INT "$pid"
wait "$pid" || fail "the run failed"
pid=

# The reload's header, once, between step S and step S + 1 of one numbering.
[ "$(grep -c '"reload": ' "$work/trace.jsonl")" -eq 1 ] || fail "not one reload in the trace"
line=$(grep -n '"reload": 1, "after_step": ' "$work/trace.jsonl" | cut -d: -f1)
sed -n "${line}p" "$work/trace.jsonl" >"$work/header.json"
after=$(value "$work/header.json" after_step)
sed -n "$((line - 1))p" "$work/trace.jsonl" >"$work/before.json"
sed -n "$((line + 1))p" "$work/trace.jsonl" >"$work/next.json"
[ "$(value "$work/before.json" step)" -eq "$after" ] || fail "the step before the reload is not $after"
[ "$(value "$work/next.json" step)" -eq $((after + 1)) ] ||
  fail "the step after the reload is not $((after + 1))"
grep -q "^step *$after  reloaded carried" "$work/out.txt" ||
  fail "the terminal does not name step $after for the reload"
# The edit from that step on, not before.
[ "$(value "$work/before.json" layers main ticker requested)" = 1.0 ] || fail "edited before"
[ "$(value "$work/next.json" layers main ticker requested)" = 0.5 ] || fail "not edited after"
# The machine carried on: its next cycle, in the state it had reached.
cycle=$(value "$work/before.json" controllers plan cycle)
[ "$cycle" -gt 3 ] || fail "the machine had not run before the reload"
[ "$(value "$work/next.json" controllers plan cycle)" -eq $((cycle + 1)) ] ||
  fail "the machine's cycle did not carry over: $(value "$work/next.json" controllers)"
[ "$(value "$work/before.json" controllers plan state)" = second ] || fail "not in state second"
[ "$(value "$work/next.json" controllers plan state)" = second ] ||
  fail "the machine's state did not carry over: $(value "$work/next.json" controllers)"
echo "reloaded after step $after; the machine carried on at cycle $((cycle + 1)) in state second"
