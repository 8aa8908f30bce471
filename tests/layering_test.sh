#!/usr/bin/env bash
# The engine's folders are its stages (engine/CMakeLists.txt lists them in data-path order, core
# before tools); a file may include its own stage and the stages before it, never a later one:
# core never includes tools, and no stage reaches back up the data path.
#   layering_test.sh ENGINE_DIR "CORE STAGES..." "TOOLS STAGES..."
set -euo pipefail
engine=$1
IFS=" ;" read -ra core <<<"$2"
IFS=" ;" read -ra tools <<<"$3"

declare -A rank  # "core/model" -> 3
n=0
for stage in "${core[@]}"; do rank[core/$stage]=$((n += 1)); done
for stage in "${tools[@]}"; do rank[tools/$stage]=$((n += 1)); done

# Which stage a public header belongs to: the folder whose arbiter/ holds it.
declare -A header_stage  # "manager.hpp" -> "core/run"
for stage in "${!rank[@]}"; do
  [[ -d $engine/$stage ]] || { echo "FAILED: stage folder $engine/$stage is missing"; exit 1; }
  for header in "$engine/$stage"/arbiter/*.hpp; do
    [[ -e $header ]] && header_stage[$(basename "$header")]=$stage
  done
done

failed=0
checked=0
while IFS= read -r -d '' file; do
  relative=${file#"$engine"/}
  own=$(cut -d/ -f1-2 <<<"$relative")
  if [[ -z ${rank[$own]:-} ]]; then
    echo "FAILED: $relative is in no stage folder of engine/CMakeLists.txt"
    failed=1
    continue
  fi
  while IFS=: read -r line include; do
    if [[ $include =~ ^arbiter/(.+)$ ]]; then
      target=${header_stage[${BASH_REMATCH[1]}]:-}
      if [[ -z $target ]]; then
        echo "FAILED: $relative:$line includes $include, which no stage has"
        failed=1
        continue
      fi
    elif [[ $include =~ ^((core|tools)/[a-z_]+)/ ]]; then
      target=${BASH_REMATCH[1]}
      if [[ ! -e $engine/$include ]]; then
        echo "FAILED: $relative:$line includes $include, which does not exist"
        failed=1
        continue
      fi
    else
      echo "FAILED: $relative:$line includes \"$include\": a private header is included by its path from engine/"
      failed=1
      continue
    fi
    checked=$((checked + 1))
    if ((rank[$target] > rank[$own])); then
      echo "FAILED: $relative:$line ($own) includes $include of the later stage $target"
      failed=1
    fi
  done < <(grep -nE '^#include ["<](arbiter/|core/|tools/|[a-z_]+\.hpp")' "$file" |
    sed -E 's/^([0-9]+):#include ["<]([^">]+)[">].*/\1:\2/')
done < <(find "$engine/core" "$engine/tools" -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0)

[[ $failed -eq 0 ]] && echo "ok: $checked includes between ${#rank[@]} stages, none up the data path"
exit $failed
