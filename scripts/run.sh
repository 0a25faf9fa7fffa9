#!/usr/bin/env bash
# First README command: install what is missing, build, and start the appliance (epa serve) on the
# embedded sim plant with config/epa.toml. Extra arguments go to `epa serve`, e.g.
#   scripts/run.sh --mode run --setpoint 100      # start in RUN and move the simulated piston
# Stop it with Ctrl-C (SIGINT) or SIGTERM: the valve goes to its safe command first.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target epa
exec build/release/src/app/epa serve --config config/epa.toml "$@"
