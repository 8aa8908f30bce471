#!/bin/bash
# tests/tutorial_test.sh fails, at the tutorial's line, when a page shows an output its command does
# not print or has a command that fails (tests/data/tutorial/): so the tutorial's test cannot pass
# by checking nothing. Arguments: tutorial_test.sh, the SDK prefix, tests/data/tutorial.
set -u
script=$1
prefix=$2
pages=$3
failed=0
expect_failure() {  # PAGE MESSAGE
  local out status=0
  out=$(bash "$script" "$prefix" "$pages/$1" 2>&1) || status=$?
  if [ "$status" -ne 1 ] || ! grep -qF "$2" <<<"$out"; then
    echo "FAIL: $1: expected exit 1 and '$2', got exit $status:"
    echo "$out"
    failed=1
  fi
}
expect_failure wrong_output.md \
  "FAIL: wrong_output.md:7: the block at line 3 did not print, in this order: hello, world"
expect_failure failing_command.md "FAIL: failing_command.md:8: the block exited 1"
[ "$failed" -eq 0 ] && echo "the tutorial's test fails where the page is wrong: 2 passed, 0 failed"
exit "$failed"
