#!/usr/bin/env bash
# Installs what is missing, then builds and tests the project four ways; exits non-zero on any failure:
#   plain  the build a packager or a newcomer runs (`cmake -S . -B build/plain`: no preset,
#          no option, GCC): any compiler warning fails it; then the whole test suite;
#   clang  the clang preset (Clang, Debug, warnings as errors) and the test suite;
#   asan   the asan preset (AddressSanitizer and UndefinedBehaviorSanitizer) and the test suite, when
#          the compiler's sanitizers work on this machine;
#   fuzz   the libFuzzer targets for a short while (fuzz/, docs/robustness.md).
# ccache is used when it is installed.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

jobs=${ARBITER_JOBS:-$(nproc 2>/dev/null || echo 2)}
# Keep in step with the asan test preset; exported here too because catch_discover_tests runs the
# test binary during the build.
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:check_initialization_order=1:strict_init_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}

summaries=()

# A compiler cache, when there is one, shared by every build of this checkout (and of another
# checkout at another path: the paths are hashed relative to the checkout).
if command -v ccache >/dev/null; then
  export CMAKE_CXX_COMPILER_LAUNCHER=ccache CCACHE_BASEDIR=$PWD CCACHE_NOHASHDIR=1
fi

# Runs ctest for build NAME with the remaining arguments; records its counts as
# "NAME: N passed, N failed".
run_tests() {
  local name=$1 log status=0 counts
  shift
  echo "== $name: test"
  log=$(mktemp)
  ctest "$@" --output-on-failure --no-tests=error --parallel "$jobs" 2>&1 | tee "$log" || status=$?
  counts=$(sed -nE 's/.*tests passed, ([0-9]+) tests? failed out of ([0-9]+).*/\1 \2/p' "$log" | tail -1)
  rm -f "$log"
  if [[ -n $counts ]]; then
    local failed=${counts% *} total=${counts#* }
    summaries+=("$name: $((total - failed)) passed, $failed failed")
  else
    summaries+=("$name: tests did not run")
  fi
  return "$status"
}

# Configures, builds and tests one preset. Arguments after the preset go to ctest.
run_preset() {
  local preset=$1
  shift
  echo "== $preset: configure and build"
  cmake --preset "$preset" --log-level=WARNING
  cmake --build --preset "$preset" --parallel "$jobs"
  run_tests "$preset" --preset "$preset" "$@"
}

# The conventional build, exactly as a packager or a FetchContent user runs it: no preset, no
# option, the default generator. Warnings are not errors there (a newer compiler's new warning must
# not break someone's build), so this job counts them itself: GCC warns at -O2 where the Debug
# presets see nothing (-Wmaybe-uninitialized).
run_plain() {
  local dir=build/plain log status=0 warnings
  echo "== plain: cmake -S . -B $dir && cmake --build $dir"
  cmake -S . -B "$dir" --log-level=WARNING
  # With no build type given, the project builds Release (CMakeLists.txt), not unoptimised.
  if ! grep -qx 'CMAKE_BUILD_TYPE:STRING=Release' "$dir/CMakeCache.txt"; then
    echo "== plain: a build with no CMAKE_BUILD_TYPE is not Release: $(grep '^CMAKE_BUILD_TYPE:' "$dir/CMakeCache.txt")"
    summaries+=("plain: the default build type is not Release")
    return 1
  fi
  log=$(mktemp)
  cmake --build "$dir" --parallel "$jobs" 2>&1 | tee "$log" || status=$?
  warnings=$(grep -c -E '(^|: )warning: ' "$log" || true)
  rm -f "$log"
  if [[ $status -ne 0 ]]; then
    summaries+=("plain: the build failed")
    return "$status"
  fi
  if [[ $warnings -ne 0 ]]; then
    echo "== plain: the build printed $warnings compiler warning(s), above; fix them"
    summaries+=("plain: $warnings compiler warning(s)")
    return 1
  fi
  run_tests plain --test-dir "$dir"
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
      -DARBITER_WARNINGS_AS_ERRORS=ON \
      --log-level=WARNING
  cmake --build "$dir" --target arbiter_fuzz_config arbiter_fuzz_trace arbiter_fuzz_replay \
      arbiter_fuzz_scene --parallel "$jobs"
  # The config loader gets two fifths of the time; the trace reader, replay and the recorded
  # picture a fifth each.
  local config_seconds=$((seconds * 2 / 5))
  local trace_seconds=$((seconds / 5))
  local scene_seconds=$((seconds / 5))
  local replay_seconds=$((seconds - config_seconds - trace_seconds - scene_seconds))
  echo "== fuzz: ${config_seconds} s config, ${trace_seconds} s trace, ${replay_seconds} s replay," \
       "${scene_seconds} s scene"
  work=$(mktemp -d)
  fuzz/make_seeds.sh "$work/seeds" >/dev/null
  fuzz/make_seeds.sh "$work/trace_seeds" trace >/dev/null
  fuzz/make_seeds.sh "$work/scene_seeds" scene >/dev/null
  # Recordings made by the arbiter the plain job built.
  fuzz/make_seeds.sh "$work/replay_seeds" replay build/plain/cli/arbiter >/dev/null
  mkdir -p "$work/corpus" "$work/trace_corpus" "$work/replay_corpus" "$work/scene_corpus"
  "$dir/fuzz/arbiter_fuzz_config" -dict=fuzz/config.dict -max_total_time="$config_seconds" \
      -timeout=5 -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/" \
      "$work/corpus" "$work/seeds" </dev/null >"$work/fuzz.log" 2>&1 || status=$?
  if [[ $status -eq 0 ]]; then
    "$dir/fuzz/arbiter_fuzz_trace" -max_total_time="$trace_seconds" -timeout=5 \
        -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/" \
        "$work/trace_corpus" "$work/trace_seeds" </dev/null >>"$work/fuzz.log" 2>&1 || status=$?
  fi
  if [[ $status -eq 0 ]]; then
    "$dir/fuzz/arbiter_fuzz_replay" -max_total_time="$replay_seconds" -timeout=5 \
        -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/" \
        "$work/replay_corpus" "$work/replay_seeds" </dev/null >>"$work/fuzz.log" 2>&1 || status=$?
  fi
  if [[ $status -eq 0 ]]; then
    "$dir/fuzz/arbiter_fuzz_scene" -max_total_time="$scene_seconds" -timeout=5 \
        -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/" \
        "$work/scene_corpus" "$work/scene_seeds" </dev/null >>"$work/fuzz.log" 2>&1 || status=$?
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
# (web/tests/) and the schema's ajv test (tests/schema/), xmllint for the plot test. Looked for by command, so that a Node.js installed
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
# make for the plain build's default generator; Clang for the clang preset and, with its runtime
# (libFuzzer, sanitizers), for the fuzz job.
command -v make >/dev/null || test_tools+=(make)
command -v clang++ >/dev/null || test_tools+=(clang)
test_tools+=(libclang-rt-dev)
# pytest runs the Python module's tests; pandas is what its recordings turn into.
test_tools+=(python3-pytest python3-pandas)
scripts/install-deps.sh "${test_tools[@]}"

status=0
run_plain || status=$?
if [[ $status -eq 0 ]]; then
  # The browser tests exercise the page, not the engine: once, in the plain build, is enough.
  run_preset clang --label-exclude browser || status=$?
fi
if [[ $status -eq 0 ]]; then
  if sanitizers_work; then
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
