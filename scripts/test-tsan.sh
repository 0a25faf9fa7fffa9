#!/usr/bin/env bash
# The threaded tests under ThreadSanitizer (preset tsan: g++ -O1 -g1, build/tsan): the
# scan cycle and its channels (runtime_test), the Modbus server over loopback (modbus_test), the
# store thread (store_test), the HTTP server (web_test), the remote I/O backend against its
# simulator (hal_test) and the model-health monitor's thread (appliance_test). Only those
# executables are built. Suppressions (scripts/tsan.supp) are
# for third-party code only, each with its reason. Extra arguments go to ctest; --build-only
# alone builds and stops.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
tests=(runtime_test modbus_test store_test web_test hal_test appliance_test)
start=$(date +%s)
cmake --preset tsan >/dev/null
cmake --build --preset tsan --target "${tests[@]}"
built=$(date +%s)
[ "${1:-}" = --build-only ] && exit 0  # .ci/run compiles ahead while the release suite runs
ctest --preset tsan -L "^($(IFS='|'; echo "${tests[*]}"))\$" "$@"
echo "test-tsan: build $((built - start)) s, tests $(($(date +%s) - built)) s"
