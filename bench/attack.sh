#!/usr/bin/env bash
# The attack suite of tests/hardening/attack_test.py (raw sockets: unlock brute force and scope,
# idle and slow connections against the client cap, absurd configurations, a spreadsheet's map),
# with the idle and slow connections held for SECONDS while a client polls (ctest holds them 8 s).
#
#   bench/attack.sh [SECONDS=60]
#
# Prints every row and the share of polls served within 1 s; exit 1 when a row fails.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
[[ $seconds =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "usage: $0 [seconds]" >&2; exit 1; }
cmake --build --preset release --target epa >/dev/null
exec /usr/bin/python3 tests/hardening/attack_test.py build/release/src/app/epa "$(pwd)" "$seconds"
