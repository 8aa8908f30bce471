#!/usr/bin/env bash
# Writes the fuzzer's seed corpus into DIR: every config under configs/ and tests/data/, each
# prefixed with the format byte config_fuzzer reads first ('0' YAML, '1' JSON).
set -euo pipefail
dir=${1:?usage: make_seeds.sh DIR}
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mkdir -p "$dir"
count=0
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
