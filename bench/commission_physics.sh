#!/usr/bin/env bash
# Commissioning, whole and offline, on the physics rig of tests/integration/commission_test.py
# through a remote I/O path whose commands reach the valve a cycle late with a given probability
# (tests/commission/commission_physics_sweep.cpp): how many runs deploy, per lateness, over
# sensor-noise seeds. About 5 s a run.
#
#   bench/commission_physics.sh [SEEDS=30] [FIRST_SEED=101] [LATE=0,0.2,0.3,0.5] [BUILD_DIR=build/release]
#
# Prints each run, the table of runs deployed per lateness and the "deployed N/M" line; exit 0
# when every run ended, whatever its verdict.
set -euo pipefail
cd "$(dirname "$0")/.."
seeds=${1:-30}
first=${2:-101}
late=${3:-0,0.2,0.3,0.5}
build=${4:-build/release}
cmake --build "$build" --target commission_physics_sweep >/dev/null
exec "$build/tests/commission_physics_sweep" --seeds "$seeds" --first "$first" --late "$late"
