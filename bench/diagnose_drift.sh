#!/usr/bin/env bash
# The drift benchmark of `epa diagnose` (tests/diag/drift/): a physics axis commissioned with epa
# excite and epa identify, then one physical parameter changed at a time (18 cases), each diagnosed
# against the commissioned model file. Prints every case, the confusion matrix and the score line.
#
#   bench/diagnose_drift.sh [BUILD_DIR=build/release]        (18 cases, about 50 s)
#   bench/diagnose_drift.sh fast [BUILD_DIR]                 (3 cases: friction, supply, a null)
#   bench/diagnose_drift.sh smoke [BUILD_DIR]                (1 case, the supply change: CI's smoke step)
#
# smoke takes every step of the script (commissioning, a case recorded, diagnosed and judged, the
# matrix, the score and check lines); fast's three cases are the release suite's diag.drift_fast.
#
# Exit 0 when it ran; the issue's thresholds (drift_benchmark.py --check) are reported on the
# "drift check" line.
set -euo pipefail
cd "$(dirname "$0")/.."
subset=()
case ${1:-} in
  fast) subset=(--fast); shift ;;
  smoke) subset=(--only '^supply-4bar$'); shift ;;
esac
build=${1:-build/release}
cmake --build "$build" --target epa >/dev/null
/usr/bin/python3 tests/diag/drift/drift_benchmark.py "$build/src/app/epa" "${subset[@]}" --check || true
