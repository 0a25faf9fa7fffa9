#!/usr/bin/env bash
# Issue 9: the unit and integration tests under AddressSanitizer + UndefinedBehaviorSanitizer
# (preset asan: g++ -O1 -g, asserts on, build/asan). Any report fails its test: UBSan halts on the
# first error and ASan always does. Extra arguments go to ctest (e.g. -R Handler).
# Nothing is left out: the allocation-counting tests replace operator new with malloc-backed
# versions, which ASan intercepts like any malloc, and the benchmarks are not ctest tests. The
# interop, crash, HIL and browser tests run the instrumented epa binary as their appliance.
# hardening.fault_injection preloads a shim (LD_PRELOAD) ahead of the ASan runtime, so the asan
# test preset sets verify_asan_link_order=0; the runtime is still loaded and intercepts as usual.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh test
start=$(date +%s)
cmake --preset asan >/dev/null
cmake --build --preset asan
built=$(date +%s)
ctest --preset asan "$@"
echo "test-sanitizers: build $((built - start)) s, tests $(($(date +%s) - built)) s"
