#!/usr/bin/env bash
# The core library (arbiter::core, the one a plugin links) holds what runs on the robot, and the
# tools library the rest: checked on the dynamic symbols of the two built libraries.
#   1. each entry point of the tools (dumps, lints, explain, breakpoints, the schema, the class catalog, trace
#      reading and diffing, reading recordings and their MCAP container, scenario tests, class
#      substitution) is defined in the tools library and not in the core one: a robot writes
#      recordings, it does not read them;
#   2. the core library leaves no arbiter symbol undefined: it calls nothing in the tools library.
#   core_library_test.sh CORE_LIBRARY TOOLS_LIBRARY
set -euo pipefail
core=$1
tools=$2

# "arbiter::lint(arbiter::Model const&, ...)" per line, for the symbols `nm` selects with $2.
symbols() { nm -D -C "$2" "$1" | sed -E 's/^[0-9a-f ]* [A-Za-z] //'; }
core_defined=$(symbols "$core" --defined-only)
tools_defined=$(symbols "$tools" --defined-only)
core_undefined=$(symbols "$core" --undefined-only)

failed=0
for entry in dump_text dump_dot dump_json explain check_trace_header parse_condition seek lint lint_codes \
    config_schema catalog_text catalog_json read_trace open_trace diff_traces read_scenario \
    run_scenario substitute read_recorded_run mcap::Reader::next; do
  pattern="^arbiter::$entry(\[abi:[a-z0-9]+\])?\("  # functions returning std::string carry a tag
  if ! grep -qE "$pattern" <<<"$tools_defined"; then
    echo "FAILED: arbiter::$entry is not defined in $tools"
    failed=1
  fi
  if grep -E "$pattern" <<<"$core_defined"; then
    echo "FAILED: arbiter::$entry (above) is defined in the core library $core"
    failed=1
  fi
done
if grep "arbiter::" <<<"$core_undefined"; then
  echo "FAILED: the core library $core needs the arbiter symbols above from another library"
  failed=1
fi
[[ $failed -eq 0 ]] && echo "ok: $(wc -l <<<"$core_defined") symbols in the core library, none of the tools"
exit $failed
