#!/usr/bin/env bash
# The model-health monitor end to end over modbus-io against the drifting physics plant-server
# (bench/health_hil.py): the axis identified as a commissioning engineer does it
# (bench/physics_axis.sh), then per case 70 moves in real time with one physical change after 32.
#
#   bench/health_hil.sh [BUILD_DIR=build/release] [MOVES=70] [CHANGE_AT=32] [--law LAW] [CASE ...]
#
# Prints each case and "health hil: N of M changes named, median K moves after the change, latest
# L; false alarms F in U unchanged moves". About 2 minutes a case. CI's smoke step runs one short
# case (the scripts still run; the figures need the defaults).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
moves=${2:-70}
change_at=${3:-32}
shift $(($# < 3 ? $# : 3))
epa="$build/src/app/epa"
[ -x "$epa" ] || { echo "health_hil: build $epa first" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/physics_axis.sh
commission_physics_axis "$epa" "$work" health_hil
python3 bench/health_hil.py "$epa" "$work/physics-model.toml" "$moves" "$change_at" "$@"
