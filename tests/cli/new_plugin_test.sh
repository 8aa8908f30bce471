#!/bin/bash
# `arbiter new plugin NAME [DIR]` writes the template's files, NAME put in, and nothing else; a
# name that cannot name a plugin, or a directory in the way, is refused with the reason and
# leaves the disk as it was. (tests/cli/new_plugin_build.cmake builds what it writes.)
# Arguments: the built arbiter, the template (cli/templates/plugin).
set -eu
cli=$1
template=$2
# shellcheck source=expect.sh
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
cd "$work"

# Every file of the template, and only those, with @NAME@ replaced in paths and text.
expect_exit 0 "$cli" new plugin rover
while read -r file; do
  written=rover/${file//@NAME@/rover}
  [ -f "$written" ] || fail "no $written"
  cmp -s "$written" <(sed 's/@NAME@/rover/g' "$template/$file") ||
    fail "$written is not the template's $file with the name put in"
done < <(cd "$template" && find . -type f | sort)
[ "$(find rover -type f | wc -l)" -eq "$(find "$template" -type f | wc -l)" ] ||
  fail "more files written than the template has: $(find rover -type f)"
! grep -rq '@NAME@' rover || fail "a placeholder is left: $(grep -rl '@NAME@' rover)"
grep -q '^  cmake -S rover -B rover/build$' out.txt || fail "no next steps printed"
grep -q '^  arbiter --plugin-path rover/build run rover/rover.yaml$' out.txt ||
  fail "no run command printed"

# Nothing is overwritten: a directory that is not empty, or a file, is refused as a whole.
echo "// mine" >rover/src/stop.cpp
before=$(find rover -type f -exec md5sum {} + | sort)
expect_exit 2 "$cli" new plugin rover
grep -q "the directory 'rover' is not empty (it has '[^']*'); nothing was written" err.txt ||
  fail "no reason given for a full directory"
expect_exit 2 "$cli" new plugin other rover/src/stop.cpp
grep -q "'rover/src/stop.cpp' exists and is not a directory; nothing was written" err.txt ||
  fail "no reason given for a file in the way"
[ "$(find rover -type f -exec md5sum {} + | sort)" = "$before" ] || fail "rover/ was changed"

# An empty directory is taken, and so is one to make, however deep.
mkdir empty
expect_exit 0 "$cli" new plugin probe empty
{ [ -f empty/probe.yaml ] && [ -f empty/tests/probe.test.yaml ]; } || fail "empty/ not filled"
expect_exit 0 "$cli" new plugin deep a/b/c
[ -f a/b/c/src/plugin.cpp ] || fail "a/b/c/ not made"

# refused NAME REASON [NOTE]: exit 2, the reason and the note on stderr, no directory made.
refused() {
  expect_exit 2 "$cli" new plugin "$1"
  grep -qF "arbiter new plugin: '$1' cannot name a plugin: $2" err.txt ||
    fail "'$1': expected the reason '$2'"
  if [ $# -gt 2 ]; then grep -qF "note: $3" err.txt || fail "'$1': expected the note '$3'"; fi
  [ ! -e "$1" ] || fail "'$1' was made"
}
refused my-robot "it has '-' in it: only letters, digits and '_' are allowed" \
  "did you mean 'my_robot'?"
refused "two words" "it has ' ' in it" "did you mean 'two_words'?"
refused 3d "it does not start with a letter"
refused _x "it does not start with a letter"
refused a__b "it has '__' in it, which C++ keeps for the implementation"
refused rover_ "it ends with '_', which would put '__' in its C++ namespace, rover__plugin"
refused class "it is a C++ keyword"
refused namespace "it is a C++ keyword"
refused all "it is a target name CMake keeps for itself"
refused arbiter "it is taken"
refused "$(printf 'x%.0s' {1..65})" "it has 65 characters; at most 64 are allowed"
expect_exit 2 "$cli" new plugin ""
grep -qF "cannot name a plugin: it is empty" err.txt || fail "an empty name is not refused"
expect_exit 0 "$cli" new plugin "$(printf 'x%.0s' {1..64})"
expect_exit 0 "$cli" new plugin Rover_2

# Usage errors name the command as typed, and a misspelt kind of project the one meant.
expect_exit 2 "$cli" new plugn rover
grep -qF "arbiter new: these arguments were not expected: plugn rover" err.txt ||
  fail "'new plugn' not told"
grep -qF "note: 'plugn': did you mean 'plugin'?" err.txt || fail "no 'plugin' offered for 'plugn'"
expect_exit 2 "$cli" new
grep -qF "arbiter new: say what to start: 'arbiter new plugin NAME [DIR]'" err.txt ||
  fail "'new' alone not told"
expect_exit 2 "$cli" new plugin x y z
grep -qF "arbiter new plugin: this argument was not expected: z" err.txt ||
  fail "an extra argument not told"
grep -qF "Run 'arbiter new plugin --help'" err.txt || fail "no help for 'new plugin' offered"
{ [ ! -e x ] && [ ! -e y ]; } || fail "a usage error wrote files"

echo "arbiter new plugin writes the template and refuses what it must: 1 passed, 0 failed"
