#!/usr/bin/env bash
# Installs what is missing, builds the dev preset and runs the whole test suite, then builds and runs it
# again under AddressSanitizer and UndefinedBehaviorSanitizer (preset asan) when the compiler's
# sanitizers work on this machine, and fuzzes the config loader for a short while when clang's
# libFuzzer is installed (fuzz/, docs/robustness.md). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

jobs=${ARBITER_JOBS:-$(nproc 2>/dev/null || echo 2)}
# Keep in step with the asan test preset; exported here too because catch_discover_tests runs the
# test binary during the build.
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:check_initialization_order=1:strict_init_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}

summaries=()

# Configures, builds and tests one preset; records ctest's counts as "preset: N passed, N failed".
# Arguments after the preset go to ctest.
run_preset() {
  local preset=$1 log
  shift
  echo "== $preset: configure and build"
  cmake --preset "$preset" --log-level=WARNING
  cmake --build --preset "$preset" --parallel "$jobs"
  echo "== $preset: test"
  log=$(mktemp)
  local status=0
  ctest --preset "$preset" --output-on-failure --parallel "$jobs" "$@" 2>&1 | tee "$log" || status=$?
  local counts
  counts=$(sed -nE 's/.*tests passed, ([0-9]+) tests? failed out of ([0-9]+).*/\1 \2/p' "$log" | tail -1)
  rm -f "$log"
  if [[ -n $counts ]]; then
    local failed=${counts% *} total=${counts#* }
    summaries+=("$preset: $((total - failed)) passed, $failed failed")
  else
    summaries+=("$preset: tests did not run")
  fi
  return "$status"
}

# True when the C++ compiler CMake will pick builds and runs a program with both sanitizers.
sanitizers_work() {
  local cxx=${CXX:-c++} dir status=0
  command -v "$cxx" >/dev/null || return 1
  dir=$(mktemp -d)
  printf '#include <vector>\nint main() { std::vector<int> v(3); return v[1]; }\n' >"$dir/probe.cpp"
  "$cxx" -fsanitize=address,undefined -fno-omit-frame-pointer "$dir/probe.cpp" -o "$dir/probe" \
      >/dev/null 2>&1 && timeout 60 "$dir/probe" >/dev/null 2>&1 || status=$?
  rm -rf "$dir"
  return "$status"
}

# True when clang++ builds and runs a libFuzzer target with the sanitizers.
fuzzer_works() {
  local dir status=0
  command -v clang++ >/dev/null || return 1
  dir=$(mktemp -d)
  printf '#include <cstddef>\n#include <cstdint>\nextern "C" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }\n' >"$dir/probe.cpp"
  clang++ -fsanitize=fuzzer,address,undefined "$dir/probe.cpp" -o "$dir/probe" >/dev/null 2>&1 &&
      timeout 60 "$dir/probe" -runs=10 >/dev/null 2>&1 || status=$?
  rm -rf "$dir"
  return "$status"
}

# A short libFuzzer run over the seeds (configs/, tests/data/); any crash, leak or hang fails.
run_fuzz_smoke() {
  local seconds=${ARBITER_FUZZ_SECONDS:-45} dir=build/fuzz work status=0
  echo "== fuzz: build (clang, libFuzzer + address + undefined)"
  CXX=clang++ cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DARBITER_BUILD_FUZZERS=ON -DARBITER_BUILD_TESTS=OFF -DARBITER_BUILD_BENCHMARKS=OFF \
      --log-level=WARNING
  cmake --build "$dir" --target arbiter_fuzz_config arbiter_fuzz_trace --parallel "$jobs"
  # The config loader gets two thirds of the time, the trace reader the rest.
  local config_seconds=$((seconds * 2 / 3))
  local trace_seconds=$((seconds - config_seconds))
  echo "== fuzz: ${config_seconds} s config, ${trace_seconds} s trace"
  work=$(mktemp -d)
  fuzz/make_seeds.sh "$work/seeds" >/dev/null
  fuzz/make_seeds.sh "$work/trace_seeds" trace >/dev/null
  mkdir -p "$work/corpus" "$work/trace_corpus"
  "$dir/fuzz/arbiter_fuzz_config" -dict=fuzz/config.dict -max_total_time="$config_seconds" \
      -timeout=5 -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/" \
      "$work/corpus" "$work/seeds" </dev/null >"$work/fuzz.log" 2>&1 || status=$?
  if [[ $status -eq 0 ]]; then
    "$dir/fuzz/arbiter_fuzz_trace" -max_total_time="$trace_seconds" -timeout=5 \
        -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/" \
        "$work/trace_corpus" "$work/trace_seeds" </dev/null >>"$work/fuzz.log" 2>&1 || status=$?
  fi
  grep -E '^(stat::number_of_executed_units|stat::average_exec_per_sec|Done)' "$work/fuzz.log" || true
  if [[ $status -eq 0 ]]; then
    summaries+=("fuzz: ${seconds} s, no crash, leak or hang")
  else
    tail -n 60 "$work/fuzz.log"
    echo "== fuzz: failed; the input is in $work (make it a test in tests/data/hostile/ or," \
         "for a trace, tests/data/bad_traces/)"
    summaries+=("fuzz: FAILED (see $work)")
  fi
  [[ $status -ne 0 ]] || rm -rf "$work"
  return "$status"
}

print_summary() {
  local line
  for line in "${summaries[@]}"; do echo "$line"; done
}

# Tools only tests use: Chromium, Node.js and npm for the browser tests of the web view
# (tests/web/) and the schema's ajv test (tests/schema/), xmllint for the plot test. Looked for by command, so that a Node.js installed
# some other way counts.
test_tools=()
command -v chromium >/dev/null || test_tools+=(chromium)
command -v node >/dev/null || test_tools+=(nodejs)
command -v npm >/dev/null || test_tools+=(npm)
command -v xmllint >/dev/null || test_tools+=(libxml2-utils)
command -v curl >/dev/null || test_tools+=(curl)
# Fast DDS, a stand-in ROS 2 node for the DDS bridge's tests (tests/dds/fastdds_peer.cpp), with
# fastddsgen, which runs on Java, to generate its message types.
test_tools+=(libfastrtps-dev fastddsgen)
command -v java >/dev/null || test_tools+=(default-jre-headless)
# Neovim for the language server's editor test (tests/lsp/).
command -v nvim >/dev/null || test_tools+=(neovim)
scripts/install-deps.sh "${test_tools[@]}"

status=0
run_preset dev || status=$?
if [[ $status -eq 0 ]]; then
  if sanitizers_work; then
    # The browser tests exercise the page, not the engine: once, in the dev preset, is enough.
    run_preset asan --label-exclude browser || status=$?
  else
    echo "== asan: skipped, this compiler's address/undefined sanitizers do not run here"
  fi
fi
if [[ $status -eq 0 ]]; then
  if fuzzer_works; then
    run_fuzz_smoke || status=$?
  else
    echo "== fuzz: skipped, clang++ with libFuzzer (e.g. Debian's libclang-rt-14-dev) is not installed"
  fi
fi
echo
print_summary
exit "$status"
