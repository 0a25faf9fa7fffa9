#!/usr/bin/env bash
# The blind test of `epa diagnose` (tests/diag/blind/): rigs whose effects are written from
# physics in forms the diagnosis does not fit, 6 training + 3 held-out runs each, scored as the
# withheld benchmark scores them. Prints every case, the confusion matrix and the score line.
#
#   bench/diagnose_blind.sh [SEEDS=2] [BUILD_DIR=build/release]     (38 cases per seed)
#   bench/diagnose_blind.sh fast                                    (11 cases: one per phenomenon)
#   bench/diagnose_blind.sh smoke                                   (1 case: CI's smoke step)
#
# Then the friction rigs on the physics plant (5 per seed; fast and smoke: one LuGre rig), with
# their own score line ("physics friction score"). smoke takes every step of both scripts (runs
# written, commissioned, diagnosed, judged; the matrix, the score and check lines) on one rig each,
# the blind set's breakpoints-out and the LuGre rig commissioned on 30-s excitations instead of
# 90: about 15 s where fast takes 95, and its scores say nothing.
#
# Exit 0 when it ran; the thresholds (tests/diag/blind/blind_diagnosis.py --check) are reported
# on the "blind check" line.
set -euo pipefail
cd "$(dirname "$0")/.."
arg=${1:-2}
build=${2:-build/release}
cmake --build "$build" --target epa >/dev/null
case $arg in
  fast) set -- --fast ;;
  smoke) set -- --only '^breakpoints-out$' ;;
  *)
    [[ $arg =~ ^[0-9]+$ ]] || { echo "usage: $0 [SEEDS|fast|smoke] [BUILD_DIR]" >&2; exit 1; }
    set -- --seeds "$arg"
    ;;
esac
/usr/bin/python3 tests/diag/blind/blind_diagnosis.py "$build/src/app/epa" "$@" --check || true
# The friction rigs on the physics plant (Karnopp and LuGre), commissioned with epa identify.
if [ "$arg" = fast ]; then
  /usr/bin/python3 tests/diag/blind/physics_friction_rigs.py "$build/src/app/epa" --fast
elif [ "$arg" = smoke ]; then
  /usr/bin/python3 tests/diag/blind/physics_friction_rigs.py "$build/src/app/epa" --fast --excite-seconds 30
else
  /usr/bin/python3 tests/diag/blind/physics_friction_rigs.py "$build/src/app/epa" --seeds "$arg"
fi
