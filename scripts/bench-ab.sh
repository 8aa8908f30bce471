#!/usr/bin/env bash
# A/B benchmarks of the working tree against a base revision (docs/performance.md, "Reporting
# benchmarks in a change"): builds arbiter_bench of both in release build trees of their own
# (through ccache where installed), runs them in turn (base, new, base, new, ...) so that both
# see the same load, and prints one row per benchmark: the medians of its CPU time per iteration,
# their ratio and a flag where the ratio is beyond the noise threshold.
#
#   scripts/bench-ab.sh [-n ROUNDS] [-t PERCENT] [BASE_REV] [FILTER] [-- BENCH_FLAGS...]
#
# BASE_REV defaults to the previous release: the newest tag v* reachable from HEAD, else the
# commit in bench/baseline.txt. FILTER is a --benchmark_filter regex (default: the
# step at N = 1000 of the none and dag graphs, and the SCL plans); BENCH_FLAGS
# go to both binaries as they are (e.g. --benchmark_min_time=0.2). The working tree is built as
# it is, uncommitted changes included.
set -euo pipefail

usage() {
  sed -n '/^#   scripts/,/^# it is/p' "$0" | sed 's/^# \{0,1\}//'
  cat <<'EOF'

  -n ROUNDS   runs of each binary, alternated (default 3)
  -t PERCENT  flag a ratio beyond 1 +- PERCENT/100 (default 10)
Build trees: build/bench-ab-new (the working tree) and build/bench-ab-base/build/release (the
base, exported from git to build/bench-ab-base); the runs' output: build/bench-ab-results.
Jobs: CMAKE_BUILD_PARALLEL_LEVEL (default 2).
EOF
}

rounds=3
threshold=10
while getopts "n:t:h" option; do
  case $option in
    n) rounds=$OPTARG ;;
    t) threshold=$OPTARG ;;
    h) usage; exit 0 ;;
    *) usage >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
positional=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
  positional+=("$1")
  shift
done
[ "${1:-}" = "--" ] && shift
extra=("$@")
if [ ${#positional[@]} -gt 2 ]; then
  usage >&2
  exit 2
fi
case $rounds in '' | *[!0-9]* | 0) echo "bench-ab: -n takes a count of 1 or more" >&2; exit 2 ;; esac
case $threshold in '' | *[!0-9.]*) echo "bench-ab: -t takes a percentage" >&2; exit 2 ;; esac

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"

# The previous release: a tag v* if there is one, else the commit bench/baseline.txt records.
previous_release() {
  local tag
  if tag=$(git describe --tags --abbrev=0 --match 'v*' HEAD 2>/dev/null); then
    echo "$tag"
    return
  fi
  local commit
  commit=$(grep -v '^[[:space:]]*\(#\|$\)' bench/baseline.txt 2>/dev/null | head -n 1 | awk '{print $1}')
  if [ -z "$commit" ]; then
    echo "bench-ab: no tag v* and no commit in bench/baseline.txt; give BASE_REV" >&2
    exit 2
  fi
  echo "$commit"
}

base_rev=${positional[0]:-}
[ -n "$base_rev" ] || base_rev=$(previous_release)
filter=${positional[1]:-'^step/(none|dag)/1000$|^scl/'}
base_commit=$(git rev-parse --verify --quiet "$base_rev^{commit}") || {
  echo "bench-ab: '$base_rev' is not a commit here" >&2
  exit 2
}

export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-2}
launcher=()
if command -v ccache >/dev/null; then
  # Paths relative to the repository, so that the two trees share what did not change.
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root} CCACHE_NOHASHDIR=${CCACHE_NOHASHDIR:-1}
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

# Configures SOURCE's release preset into BUILD (tests off: only the benchmark is built) and
# builds arbiter_bench there. Both trees lie two levels below their source, as build/release
# does, so ccache finds the objects of any release build of the same sources.
build_bench() {
  local source=$1 build=$2
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$source" -B "$build" --preset release --log-level=WARNING -DARBITER_BUILD_TESTS=OFF \
      "${launcher[@]}" >/dev/null
  fi
  cmake --build "$build" --target arbiter_bench >"$build.log" 2>&1 || {
    tail -n 30 "$build.log" >&2
    echo "bench-ab: building $build failed (whole log: $build.log)" >&2
    exit 1
  }
}

# The base's source, exported from git once per commit (another base starts afresh).
base_source=$root/build/bench-ab-base
base_build=$base_source/build/release
new_build=$root/build/bench-ab-new
if [ "$(cat "$base_source.commit" 2>/dev/null)" != "$base_commit" ]; then
  rm -rf "$base_source"
  mkdir -p "$base_source"
  git archive "$base_commit" | tar -x -C "$base_source"
  echo "$base_commit" >"$base_source.commit"
fi
echo "building the base ($(git log -1 --format='%h %s' "$base_commit" | cut -c1-70))" >&2
build_bench "$base_source" "$base_build"
echo "building the working tree ($(git log -1 --format=%h HEAD)$(git diff --quiet HEAD -- || echo ', with changes'))" >&2
build_bench "$root" "$new_build"

results=$root/build/bench-ab-results
rm -rf "$results"
mkdir -p "$results"
for ((round = 1; round <= rounds; ++round)); do
  for side in base new; do
    echo "round $round/$rounds: $side" >&2
    binary=$base_build/bench/arbiter_bench
    [ $side = new ] && binary=$new_build/bench/arbiter_bench
    "$binary" --benchmark_filter="$filter" --no-target-check \
      --benchmark_out="$results/$side.$round.json" --benchmark_out_format=json "${extra[@]}" \
      >"$results/$side.$round.txt" 2>&1 || {
      cat "$results/$side.$round.txt" >&2
      echo "bench-ab: the $side benchmark failed" >&2
      exit 1
    }
  done
done

cpu_model=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -n 1)
echo "base $(git rev-parse --short "$base_commit") ($base_rev) against the working tree" \
  "($(git log -1 --format=%h HEAD)$(git diff --quiet HEAD -- || echo ', with changes'))," \
  "filter '$filter', median of $rounds alternated runs each"
echo "machine: $(nproc) cores (${cpu_model:-unknown CPU}), load average $(cut -d' ' -f1-3 /proc/loadavg);" \
  "CPU time of the benchmark thread"
echo
# Google Benchmark's JSON, one field a line: each run's name, run_type, cpu_time, time_unit and
# error_occurred become a line "side<TAB>name<TAB>ns<TAB>error". Aggregate runs (with
# --benchmark_repetitions) are left out: every repetition is a sample of its own. (The CSV format
# cannot be used: it refuses benchmarks with different counters in one run.)
for file in "$results"/*.json; do
  side=${file##*/}
  awk -v side="${side%%.*}" '
    function value(line) {
      sub(/^[^:]*:[ ]*/, "", line); sub(/,[ ]*$/, "", line); gsub(/"/, "", line)
      return line
    }
    /^[ ]*"benchmarks":/ { inside = 1 }
    !inside { next }
    /^[ ]*\{/ { name = ""; type = ""; cpu = ""; unit = "ns"; error = "false" }
    /^[ ]*"name":/ { name = value($0) }
    /^[ ]*"run_type":/ { type = value($0) }
    /^[ ]*"cpu_time":/ { cpu = value($0) }
    /^[ ]*"time_unit":/ { unit = value($0) }
    /^[ ]*"error_occurred":/ { error = value($0) }
    /^[ ]*\}/ && name != "" {
      if (type != "aggregate") {
        scale = unit == "us" ? 1e3 : unit == "ms" ? 1e6 : unit == "s" ? 1e9 : 1
        printf "%s\t%s\t%s\t%s\n", side, name, error == "true" ? "" : cpu * scale, error
      }
      name = ""
    }
  ' "$file"
done >"$results/samples.tsv"
awk -F'\t' -v threshold="$threshold" '
  function median(list,    n, values, i, j, swap) {
    n = split(list, values, " ")
    for (i = 2; i <= n; ++i) {
      for (j = i; j > 1 && values[j - 1] + 0 > values[j] + 0; --j) {
        swap = values[j]; values[j] = values[j - 1]; values[j - 1] = swap
      }
    }
    low = values[1]; high = values[n]
    return n % 2 ? values[(n + 1) / 2] : (values[n / 2] + values[n / 2 + 1]) / 2
  }
  {
    side = $1; name = $2
    if (!(name in seen)) { seen[name] = 1; order[++names] = name }
    if ($4 == "true") { failed[side, name] = 1; next }
    samples[side, name] = samples[side, name] " " $3
  }
  END {
    printf "| benchmark | base ns | new ns | new/base | base range | new range | |\n"
    printf "|---|---:|---:|---:|---:|---:|---|\n"
    for (i = 1; i <= names; ++i) {
      name = order[i]
      if (samples["base", name] == "" || samples["new", name] == "") {
        printf "| %s | %s | %s | | | | %s |\n", name,
               samples["base", name] == "" ? "-" : sprintf("%.1f", median(samples["base", name])),
               samples["new", name] == "" ? "-" : sprintf("%.1f", median(samples["new", name])),
               failed["base", name] || failed["new", name] ? "error" : "not in both"
        continue
      }
      base = median(samples["base", name]); base_low = low; base_high = high
      new = median(samples["new", name]); new_low = low; new_high = high
      ratio = base > 0 ? new / base : 0
      flag = ""
      if (ratio > 1 + threshold / 100) flag = "**slower**"
      else if (ratio > 0 && ratio < 1 - threshold / 100) flag = "faster"
      # Ranges that overlap: the runs alone cannot tell the two apart.
      if (flag != "" && (new_low <= base_high && base_low <= new_high)) flag = flag " (ranges overlap)"
      printf "| %s | %.1f | %.1f | %.2f | %.1f-%.1f | %.1f-%.1f | %s |\n", name, base, new, ratio,
             base_low, base_high, new_low, new_high, flag
    }
    printf "\nflagged: beyond +-%s %% (-t); ns: CPU time per iteration (the step benchmarks: per step)\n",
           threshold
  }
' "$results/samples.tsv"
