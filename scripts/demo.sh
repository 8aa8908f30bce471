#!/usr/bin/env bash
# Installs what is missing, builds the release preset and runs a soccer demo:
#   scripts/demo.sh [ARGS...]          the kick demo: a robot searches for the ball, walks behind
#                                      it and kicks it into the goal (ARGS replace `--steps 220`)
#   scripts/demo.sh goalie [ARGS...]   the goalie demo: the opponent's shot, the dive, the save
# Arguments go to `arbiter run`, e.g.
#   scripts/demo.sh --steps 300 --realtime --trace demo.jsonl
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

config=configs/soccer/walk_and_kick.yaml
default_args=(--steps 220)
if [ "${1:-}" = goalie ]; then
  shift
  config=configs/soccer/goalie.yaml
  default_args=()  # the config's own `steps: 240` tells the whole story
fi

scripts/install-deps.sh
# Configuring and building print pages that say nothing about the demo: they go to a log, shown
# only when a step fails.
mkdir -p build
log=build/demo-build.log
echo "building arbiter and the soccer plugin (build/release; log: $log)..."
if ! { cmake --preset release --log-level=WARNING &&
       cmake --build --preset release --target arbiter soccer \
         --parallel "${ARBITER_JOBS:-$(nproc 2>/dev/null || echo 2)}"; } >"$log" 2>&1; then
  cat "$log" >&2
  echo "scripts/demo.sh: the build failed (above; also in $log)" >&2
  exit 1
fi
if [ $# -eq 0 ]; then set -- "${default_args[@]}"; fi
exec build/release/cli/arbiter run "$config" "$@"
