#!/bin/bash
# `arbiter run` under `on_exception: stop`: the run ends after the step in which a behaviour threw,
# says who threw and where it was declared, and exits 1 (a failed run), even with --realtime and
# many steps left.
set -eu
cli=$1
plugin_dir=$2
config=$3
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
out=$work/out.txt
err=$work/err.txt

expect_exit 1 timeout 20 "$cli" run "$config" --plugin-path "$plugin_dir" --steps 100000 --realtime
grep -q "^arbiter run: stopped after step 3: .*faulty_stop.yaml:13:7: behaviour 'flaky' (test_good.Faulty) threw from execute() in step 3: sensor cable unplugged" \
  "$err" || fail "no stop message naming the behaviour and its location"
grep -q "simulated 0.20 s at 15 Hz" "$out" || fail "the run did not end with step 3"
echo "stop: 1 passed, 0 failed"
