#!/usr/bin/env bash
# The model-health monitor (src/diag/model_health.*) on the physics plant, faster than real time
# (bench/health_drift.cpp): an axis commissioned as pp_traj_tables.sh does it (three 30 s
# `epa excite` runs, `epa identify`), moves between random targets under pp-traj, and one physical
# change after 32 moves (the monitor learns its baseline on the first 24): friction x2, supply
# 4.5 bar, a break point of the overlap moved 0.25 V, the spool 3x slower, or none. Prints each
# case and the summary line.
#
#   bench/health_drift.sh [BUILD_DIR=build/release] [SEEDS=3] [MOVES=70] [extra health_drift options]
#
# CI's smoke step runs it with one seed and 40 moves.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
seeds=${2:-3}
moves=${3:-70}
shift $(($# < 3 ? $# : 3))
epa="$build/src/app/epa"
bench="$build/bench/health_drift"
[ -x "$epa" ] && [ -x "$bench" ] || { echo "health_drift: build $epa and $bench first" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/physics_axis.sh
commission_physics_axis "$epa" "$work" health_drift
"$bench" "$work/physics-model.toml" --seeds "$seeds" --moves "$moves" "$@"
