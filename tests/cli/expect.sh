# What the CLI scripts share, sourced first: it makes the scratch folder `work`, removed at exit,
# when the background process `pid` (if set) and those in `pids` are killed too.
# fail MESSAGE prints it and every $work/*.txt, then exits 1; expect_exit CODE COMMAND... runs the
# command with its output in $work/out.txt and $work/err.txt and fails unless it exits CODE;
# wait_for PATTERN FILE waits (bounded: 20 s) until `grep -q PATTERN FILE` succeeds.
work=$(mktemp -d)
pid=
pids=()
# A background job killed between its fork and its exec is still a copy of this shell, and runs
# this trap as it dies: only the script's own shell may clean up, or the copy removes `work`.
trap '[[ $BASHPID == "$$" ]] || exit; for p in $pid "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$work"' EXIT

fail() {
  echo "FAIL: $*"
  for f in "$work"/*.txt; do [[ -e $f ]] && { echo "--- $f"; cat "$f"; }; done
  exit 1
}
expect_exit() {  # CODE COMMAND...
  local code=$1 errexit=$-
  shift
  set +e
  "$@" >"$work/out.txt" 2>"$work/err.txt"
  local got=$?
  # Back as the script had it: a script without set -e does not get it from here.
  [[ $errexit != *e* ]] || set -e
  [[ $got -eq $code ]] || fail "exit $got, not $code: $*"
}
wait_for() {  # PATTERN FILE
  for _ in $(seq 1 400); do
    grep -q -- "$1" "$2" && return 0
    sleep 0.05
  done
  fail "no '$1' in $2"
}
# printed SCRIPT FILE: the first line `sed -nE SCRIPT FILE` prints (a server's URL), once there is
# one (bounded: 10 s); nothing if none comes.
printed() {
  local line
  for _ in $(seq 1 100); do
    line=$(sed -nE "$1" "$2" | head -1)
    [ -n "$line" ] && break
    sleep 0.1
  done
  echo "$line"
}
# serve_until PATTERN COMMAND...: runs a command that serves until stopped (`arbiter view`) in the
# background, with its output in $work/out.txt and $work/err.txt, until PATTERN is in err.txt or it
# exits (bounded: 60 s, for a loaded machine); then stops it.
serve_until() {
  local pattern=$1
  shift
  # Emptied first: what the previous command wrote must not pass for this one's PATTERN.
  : >"$work/out.txt"
  : >"$work/err.txt"
  "$@" >"$work/out.txt" 2>"$work/err.txt" &
  pid=$!
  for _ in $(seq 600); do
    grep -q -- "$pattern" "$work/err.txt" && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  pid=
}
# record_reload STARTED EDIT RELOADED: records `$cli run $work/robot.yaml --watch --realtime`
# to $work/run.mcap (output in $work/out.txt); once STARTED is in its output, edits the config
# with `sed -i EDIT`, and stops the run (SIGINT) a few steps after RELOADED is.
record_reload() {
  : >"$work/out.txt"
  "$cli" run "$work/robot.yaml" --watch --realtime --record "$work/run.mcap" \
    >"$work/out.txt" 2>"$work/err.txt" &
  pid=$!
  wait_for "$1" "$work/out.txt"
  sed -i "$2" "$work/robot.yaml"
  wait_for "$3" "$work/out.txt"
  sleep 0.3  # a few steps of the reloaded config
  kill -INT "$pid"
  wait "$pid" || fail "the recorded run failed"
  pid=
}
