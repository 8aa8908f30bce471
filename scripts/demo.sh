#!/usr/bin/env bash
# Installs what is missing, builds the release preset and runs the soccer demo: a robot searches
# for the ball, walks behind it and kicks it into the goal.
# Arguments replace the default `--steps 220` and go to `arbiter run`, e.g.
#   scripts/demo.sh --steps 300 --realtime --trace demo.jsonl
set -euo pipefail
config=configs/soccer/walk_and_kick.yaml
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/install-deps.sh
cmake --preset release --log-level=WARNING
cmake --build --preset release --target arbiter soccer --parallel "${ARBITER_JOBS:-$(nproc 2>/dev/null || echo 2)}"
if [ $# -eq 0 ]; then set -- --steps 220; fi
exec build/release/cli/arbiter run "$config" "$@"
