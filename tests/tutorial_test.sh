#!/bin/bash
# docs/tutorial.md as a newcomer follows it, in an empty folder, with the installed arbiter first
# on the PATH: its blocks in order, each as written.
#   ```sh            the commands run, in one folder carried from block to block (a `cd` holds);
#                    every command must succeed. A block with "until Ctrl-C" in it serves: it runs
#                    until the web address it prints answers, then gets Ctrl-C and must exit 0.
#   *FILE* above a block   the block is saved as FILE (in the current folder).
#   *FILE, in part* above a block   each of its lines is a line of FILE, in this order ("..."
#                    lines stand for lines left out).
#   ```text right after a ```sh block   what that block prints: each line is in its output, in
#                    this order ("..." lines stand for lines left out).
#   <!-- not run --> above a block   it is skipped (the set-up that the test does itself).
# A failure names the block's line in the tutorial. Arguments: the SDK prefix (bin/arbiter and the
# CMake package, installed), docs/tutorial.md.
set -u
prefix=$(cd "$1" && pwd) || { echo "FAIL: no SDK prefix $1"; exit 1; }
doc=$2
name=$(basename "$doc")
work=$(mktemp -d)
server=
trap '[[ $BASHPID == "$$" ]] || exit; [ -n "$server" ] && kill -- -"$server" 2>/dev/null; rm -rf "$work"' EXIT
export PATH="$prefix/bin:$PATH"
unset ARBITER_PLUGIN_PATH CMAKE_PREFIX_PATH
set -m  # a served block runs in a process group of its own, which Ctrl-C (SIGINT) goes to

fail() {  # LINE MESSAGE [OUTPUT FILE]
  echo "FAIL: $name:$1: $2"
  [ $# -gt 2 ] && { echo "--- $3:"; cat "$3"; }
  exit 1
}

# in_order EXPECTED ACTUAL LINE WHAT: each line of the file EXPECTED but "..." (indented or not)
# and blank ones is a whole line of ACTUAL, after the one before it; trailing blanks do not count.
in_order() {
  local at=0 expected bare found
  while IFS= read -r expected; do
    expected=${expected%"${expected##*[![:space:]]}"}
    bare=${expected#"${expected%%[![:space:]]*}"}
    [ -z "$bare" ] || [ "$bare" = "..." ] && continue
    found=$(awk -v want="$expected" -v from="$at" '
      NR > from { sub(/[ \t]+$/, ""); if ($0 == want) { print NR; exit } }' "$2")
    [ -n "$found" ] || fail "$3" "$4, in this order: $expected" "$2"
    at=$found
  done <"$1"
}

# The blocks: NNN.kind (sh, file, part, output, skip, other), NNN.line, NNN.body, NNN.file.
mkdir "$work/blocks"
awk -v dir="$work/blocks" '
  function out(n, what, text) { f = sprintf("%s/%03d.%s", dir, n, what); printf "%s", text > f; close(f) }
  inside && /^```$/ {
    inside = 0; out(n, "kind", kind); out(n, "line", start); out(n, "body", body)
    if (kind == "file" || kind == "part") out(n, "file", file)
    last_sh = (kind == "sh"); after_fence = 1; before = ""; next
  }
  inside { body = body $0 "\n"; next }
  /^```/ {
    inside = 1; n++; start = NR; body = ""; lang = substr($0, 4)
    if (before ~ /^<!-- not run/) kind = "skip"
    else if (before ~ /^\*[^*]+, in part\*$/) { kind = "part"; file = substr(before, 2, length(before) - 11) }
    else if (before ~ /^\*[^*]+\*$/) { kind = "file"; file = substr(before, 2, length(before) - 2) }
    else if (lang == "sh") kind = "sh"
    else if (lang == "text" && after_fence && last_sh) kind = "output"
    else kind = "other"
    next
  }
  /^[ \t]*$/ { next }
  { before = $0; after_fence = 0 }
' "$doc"

root=$work/tutorial
mkdir "$root"
cwd=$root
ran=0
last_out=
last_line=
for kind_file in "$work"/blocks/*.kind; do
  block=${kind_file%.kind}
  kind=$(cat "$kind_file")
  line=$(cat "$block.line")
  case "$kind" in
    file)
      file=$(cat "$block.file")
      mkdir -p "$(dirname "$cwd/$file")"
      cp "$block.body" "$cwd/$file"
      ;;
    sh)
      ran=$((ran + 1))
      out=$block.out
      started=${EPOCHREALTIME/./}
      { echo "set -e"; cat "$block.body"; echo "pwd >\"$work/cwd\""; } >"$block.sh"
      if grep -q 'until Ctrl-C' "$block.body"; then
        (cd "$cwd" && exec bash "$block.sh") >"$out" 2>&1 &
        server=$!
        url=
        for _ in $(seq 600); do
          url=$(grep -oE 'https?://[^ ]+' "$out" | head -1)
          [ -n "$url" ] && break
          kill -0 "$server" 2>/dev/null || break
          sleep 0.1
        done
        [ -n "$url" ] || fail "$line" "the block printed no web address" "$out"
        if command -v curl >/dev/null; then
          code=$(curl -s -o "$block.page" -w '%{http_code}' --max-time 20 "$url")
          [ "$code" = 200 ] || fail "$line" "$url answered $code, not 200" "$out"
        fi
        kill -INT -- -"$server"
        status=0
        wait "$server" || status=$?
        server=
        [ "$status" -eq 0 ] || fail "$line" "the block exited $status after Ctrl-C" "$out"
      else
        (cd "$cwd" && bash "$block.sh") >"$out" 2>&1 ||
          fail "$line" "the block exited $? (bash -e)" "$out"
        cwd=$(cat "$work/cwd")
      fi
      elapsed=$(((${EPOCHREALTIME/./} - started) / 1000))
      echo "$name:$line: ran in $((elapsed / 1000)).$(printf '%03d' $((elapsed % 1000))) s"
      last_out=$out
      last_line=$line
      ;;
    output)
      in_order "$block.body" "$last_out" "$line" "the block at line $last_line did not print"
      ;;
    part)
      file=$(cat "$block.file")
      [ -f "$cwd/$file" ] || fail "$line" "there is no $file to show a part of"
      in_order "$block.body" "$cwd/$file" "$line" "$file does not have"
      ;;
  esac
done
[ "$ran" -gt 0 ] || fail 1 "no sh block ran"
echo "$name: $ran command blocks ran as written: 1 passed, 0 failed"
