#!/usr/bin/env bash
# Interoperability: the npm package modbus-serial (Node.js), the whole integration an HMI does
# (tests/interop/node/flow_test.js says which steps), against a running appliance on the
# simulated plant.
#
#   modbus_serial_test.sh <epa binary> <source dir>
#
# Needs node and tests/interop/node/node_modules (scripts/install-deps.sh test runs `npm ci` there
# from the committed package-lock.json). Starts `epa serve` on a free loopback port with
# registers/epa.csv, [limits] soft_max_mm = 300 (a fault can be caused) and heartbeat_timeout_s = 5
# (the script keeps a heartbeat), runs the flow, then stops the appliance by its PID (SIGTERM,
# SIGKILL after 5 s) and expects exit status 0. Exit 0: all passed; 1: a step failed (named).
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" modbus-serial
test_arguments 2 "<epa binary> <source dir>" "$@"
node_dir="$(cd "$(dirname "$0")" && pwd)/node"
need node nodejs
need python3
# No modules: `npm ci` could not reach the npm registry (install-deps said why). Skipped (ctest's
# SKIP_RETURN_CODE 77), not passed: the summary lists it under "did not run".
[ -f "$node_dir/node_modules/modbus-serial/package.json" ] \
  || { echo "SKIP: $node_dir/node_modules has no modbus-serial: scripts/install-deps.sh test could not install it (npm registry)" >&2; exit 77; }

echo "node $(node --version), modbus-serial $(node -p "require('$node_dir/node_modules/modbus-serial/package.json').version")"
start_appliance "$src/registers/epa.csv" "[limits]
soft_max_mm = 300.0
setpoint_max_mm = 290.0
heartbeat_timeout_s = 5.0"

timeout 100 node "$node_dir/flow_test.js" "$epa" "$src" 127.0.0.1 "$port"
rc=$?
if [ $rc -eq 0 ]; then pass "the modbus-serial flow"; else fail "the modbus-serial flow exited with status $rc"; fi

finish_test
