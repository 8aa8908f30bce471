# The checks the CLI scripts share, sourced after they set `work` (a scratch folder):
# fail MESSAGE prints it and every $work/*.txt, then exits 1; expect_exit CODE COMMAND... runs the
# command with its output in $work/out.txt and $work/err.txt and fails unless it exits CODE;
# wait_for PATTERN FILE waits (bounded: 20 s) until `grep -q PATTERN FILE` succeeds.
fail() {
  echo "FAIL: $*"
  for f in "$work"/*.txt; do echo "--- $f"; cat "$f"; done
  exit 1
}
expect_exit() {  # CODE COMMAND...
  local code=$1
  shift
  set +e
  "$@" >"$work/out.txt" 2>"$work/err.txt"
  local got=$?
  set -e
  [[ $got -eq $code ]] || fail "exit $got, not $code: $*"
}
wait_for() {  # PATTERN FILE
  for _ in $(seq 1 400); do
    grep -q -- "$1" "$2" && return 0
    sleep 0.05
  done
  fail "no '$1' in $2"
}
