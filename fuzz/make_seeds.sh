#!/usr/bin/env bash
# Writes a fuzzer's seed corpus into DIR. For config_fuzzer (the default): every config under
# configs/ and tests/data/, each prefixed with the format byte it reads first ('0' YAML,
# '1' JSON). For trace_fuzzer (`make_seeds.sh DIR trace`): the traces and recordings of
# tests/data/traces/ and tests/data/bad_traces/, as they are. For replay_fuzzer
# (`make_seeds.sh DIR replay [ARBITER]`): the recordings there, a recording of each config of
# configs/paper/ made with `ARBITER run --record` (default build/dev/cli/arbiter, skipped when
# there is none), and the recorded run of tests/data/traces/ written again without chunks, so
# that the fuzzer's mutations reach the messages rather than a compressed chunk's checksum. For
# scene_fuzzer (`make_seeds.sh DIR scene`): the runs of scene messages of tests/data/scenes/, the
# first `/arbiter/scene` messages of a soccer recording and those around its second whole picture,
# one a line.
set -euo pipefail
dir=${1:?usage: make_seeds.sh DIR [config|trace|scene|replay [ARBITER]]}
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mkdir -p "$dir"
count=0

# MCAP (https://mcap.dev/spec) little-endian fields and records, as bytes on stdout.
le() {  # VALUE BYTES
  local value=$1 bytes=$2 i out=""
  for ((i = 0; i < bytes; i++)); do
    out+=$(printf '\\x%02x' $(((value >> (8 * i)) & 255)))
  done
  printf '%b' "$out"
}
str() { le "${#1}" 4; printf '%s' "$1"; }  # a string: its length (bytes, LC_ALL=C) and itself
record() {  # OPCODE CONTENT_FILE
  le "$1" 1
  le "$(wc -c <"$2")" 8
  cat "$2"
}
unchunked_recording() {  # CONFIG TRACE.jsonl: the run's header, steps and empty inputs
  local config=$1 trace=$2 tmp line step n=0
  tmp=$(mktemp -d)
  printf '\x89MCAP0\r\n'
  { str ""; str "arbiter"; } >"$tmp/c" && record 1 "$tmp/c"
  { str "version"; str "seed"; str "file:$(basename "$config")"; str "$(cat "$config")"; } >"$tmp/m"
  { str "arbiter.config"; le "$(wc -c <"$tmp/m")" 4; cat "$tmp/m"; } >"$tmp/c"
  record 12 "$tmp/c"
  local id=1 topic
  for topic in /arbiter/header /arbiter/step /arbiter/inputs; do
    { le $id 2; str "arbiter"; str "jsonschema"; str "{}"; } >"$tmp/c" && record 3 "$tmp/c"
    { le $id 2; le $id 2; str "$topic"; str "json"; le 0 4; } >"$tmp/c" && record 4 "$tmp/c"
    id=$((id + 1))
  done
  while IFS= read -r line; do
    if ((n == 0)); then
      { le 1 2; le 0 4; le 0 8; le 0 8; printf '%s' "$line"; } >"$tmp/c" && record 5 "$tmp/c"
    else
      step=${line#*\"step\": }
      step=${step%%,*}
      { le 2 2; le "$n" 4; le "$n" 8; le "$n" 8; printf '%s' "$line"; } >"$tmp/c" && record 5 "$tmp/c"
      { le 3 2; le "$n" 4; le "$n" 8; le "$n" 8; printf '{"step": %s, "inputs": {}}' "$step"; } \
        >"$tmp/c" && record 5 "$tmp/c"
    fi
    n=$((n + 1))
  done <"$trace"
  le 0 4 >"$tmp/c" && record 15 "$tmp/c"
  rm -rf "$tmp"
}

if [[ ${2:-config} == replay ]]; then
  export LC_ALL=C
  arbiter=${3:-$root/build/dev/cli/arbiter}
  for file in "$root"/tests/data/traces/*.mcap "$root"/tests/data/bad_traces/*.mcap; do
    cp "$file" "$dir/$(printf '%s' "${file#"$root"/}" | tr '/' '_')"
    count=$((count + 1))
  done
  unchunked_recording "$root/configs/paper/walk_and_kick.yaml" \
    "$root/tests/data/traces/walk_and_kick.jsonl" >"$dir/walk_and_kick_unchunked.mcap"
  count=$((count + 1))
  if [[ -x $arbiter ]]; then
    for config in "$root"/configs/paper/*.yaml; do
      "$arbiter" run "$config" --steps 20 -q --record "$dir/run_$(basename "$config" .yaml).mcap" \
        >/dev/null
      count=$((count + 1))
    done
  else
    echo "no $arbiter: no fresh recordings among the seeds" >&2
  fi
  echo "$count seeds in $dir"
  exit 0
fi
if [[ ${2:-config} == scene ]]; then
  for file in "$root"/tests/data/scenes/*; do
    cp "$file" "$dir/$(basename "$file")"
    count=$((count + 1))
  done
  echo "$count seeds in $dir"
  exit 0
fi
if [[ ${2:-config} == trace ]]; then
  for file in "$root"/tests/data/traces/* "$root"/tests/data/bad_traces/*; do
    [[ $file == *.err ]] && continue
    name=$(printf '%s' "${file#"$root"/}" | tr '/' '_')
    cp "$file" "$dir/$name"
    count=$((count + 1))
  done
  echo "$count seeds in $dir"
  exit 0
fi
while IFS= read -r -d '' file; do
  case $file in
    *.json) prefix=1 ;;
    *) prefix=0 ;;
  esac
  name=$(printf '%s' "${file#"$root"/}" | tr '/' '_')
  { printf '%s' "$prefix"; cat "$file"; } >"$dir/$name"
  count=$((count + 1))
done < <(find "$root/configs" "$root/tests/data" -type f \
           \( -name '*.yaml' -o -name '*.yml' -o -name '*.json' \) -print0)
echo "$count seeds in $dir"
