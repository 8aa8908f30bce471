#!/usr/bin/env bash
# Writes a fuzzer's seed corpus into DIR. For config_fuzzer (the default): every config under
# configs/ and tests/data/, each prefixed with the format byte it reads first ('0' YAML,
# '1' JSON). For trace_fuzzer (`make_seeds.sh DIR trace`): the traces and recordings of
# tests/data/traces/ and tests/data/bad_traces/, as they are.
set -euo pipefail
dir=${1:?usage: make_seeds.sh DIR [config|trace]}
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mkdir -p "$dir"
count=0
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
