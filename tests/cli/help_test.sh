#!/bin/bash
# The command line as a new user meets it: what --help says, the examples' files where an
# installed arbiter has them, refused options with their reason, the summary's wall time, and
# docs/cli.md's table of commands.
# Arguments: the built arbiter, the source directory, the build directory, a scratch directory.
set -u
cli=$1
source_dir=$2
build_dir=$3
work=$4
failed=0
fail() {
  echo "FAIL: $*"
  failed=1
}

commands=$("$cli" --help | sed -n '/^Subcommands:/,/^$/p' | awk '/^  [a-z]/ {print $1}')
[[ -n $commands ]] || fail "arbiter --help lists no commands"

# docs/cli.md's table has a row for every command.
for command in $commands; do
  grep -q "^| \`arbiter $command" "$source_dir/docs/cli.md" ||
    fail "docs/cli.md's table of commands lacks 'arbiter $command'"
done

# run --help says where the default number of steps comes from, and no made-up default.
run_help=$("$cli" run --help)
grep -q "default: the config's 'steps:'" <<<"$run_help" || fail "run --help: no default of --steps"
grep -q -- "--steps N " <<<"$run_help" || fail "run --help: --steps shows a default value"
# Every option that reads a run says a recording works too.
for command in explain view plot; do
  "$cli" "$command" --help | grep -q '\.mcap' || fail "$command --help: no word of .mcap"
done
# --plugin-path takes one directory per option.
"$cli" --help | grep -q -- "--plugin-path A --plugin-path B" ||
  fail "arbiter --help: --plugin-path's syntax"

# --steps 0 is refused, with the reason.
out=$("$cli" run "$source_dir/configs/paper/walk_and_kick.yaml" --steps 0 2>&1)
status=$?
[[ $status -eq 2 ]] || fail "run --steps 0: exit $status, want 2"
grep -q "0 steps would run nothing" <<<"$out" || fail "run --steps 0: no reason given: $out"

# The summary's wall time is measured, in a unit that shows it: no "0.000 s" for a short run.
out=$("$cli" run "$source_dir/configs/paper/walk_and_kick.yaml" --steps 20)
grep -Eq "in [0-9.]+ (µs|ms|s) of wall time" <<<"$out" || fail "run: no wall time: $out"
grep -q "in 0.000 s of wall time" <<<"$out" && fail "run: wall time 0.000 s"
grep -Eq "in 0(\.0+)? (µs|ms|s) of wall time" <<<"$out" && fail "run: wall time 0: $out"

# Installed, arbiter --help names the folder of the example files, and every file the examples
# of every command's --help name is there.
prefix=$work/prefix
rm -rf "$prefix"
for component in runtime plugins; do
  cmake --install "$build_dir" --prefix "$prefix" --component "$component" >/dev/null ||
    fail "cmake --install --component $component"
done
installed_cli=$prefix/bin/arbiter
share=$(cd "$prefix/share/arbiter" 2>/dev/null && pwd) || fail "no share/arbiter installed"
"$installed_cli" --help | grep -qF "run them in $share" ||
  fail "the installed arbiter --help does not name $share"
examples=$("$installed_cli" --help; for command in $commands; do "$installed_cli" "$command" --help; done)
files=$(grep -E '^  arbiter ' <<<"$examples" | grep -oE '(configs|tests)/[A-Za-z0-9_./*-]+' |
  sort -u)
[[ -n $files ]] || fail "the examples name no files"
for file in $files; do
  # A glob (configs/paper/*.yaml) names its folder; a folder ends in '/'.
  compgen -G "$share/$file" >/dev/null || [[ -d $share/${file%/} ]] ||
    fail "an example names $file, which is not installed in $share"
done
# And the installed scenario tests run from there (their configs' relative paths hold).
(cd "$share" && "$installed_cli" test tests/scenarios/paper >/dev/null) ||
  fail "the installed tests/scenarios/paper do not pass"

[[ $failed -eq 0 ]] && echo "the command line's help, refusals and examples hold"
exit $failed
