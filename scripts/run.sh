#!/usr/bin/env bash
# First README command: install what is missing, build, and run the main job.
# For now the main job is `epa simulate` on the paper's plant; extra arguments go to it.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target epa
mkdir -p out
exec build/release/src/app/epa simulate --out-dir out --json out/simulate.json --plot out/responses.svg "$@"
