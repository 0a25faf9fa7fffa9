#!/usr/bin/env bash
# The scan cycle's p99 period jitter with the model-health monitor judging every move, against
# the monitor off, in the same run (bench/health_jitter.py): the physics sim plant identified as a
# commissioning engineer does it (bench/physics_axis.sh), so the running set has a stick-slip model.
#
#   bench/health_jitter.sh [BUILD_DIR=build/release] [RUNS=3] [SECONDS=60]
#
# Prints each run and "health jitter p99: on N us / off N us = R x (bound 1.2 x)". CI's smoke
# step runs it once for a few seconds (the scripts still run; the figure needs the defaults).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
runs=${2:-3}
seconds=${3:-60}
epa="$build/src/app/epa"
[ -x "$epa" ] || { echo "health_jitter: build $epa first" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/physics_axis.sh
commission_physics_axis "$epa" "$work" health_jitter
python3 bench/health_jitter.py "$epa" "$work/physics-model.toml" "$runs" "$seconds"
