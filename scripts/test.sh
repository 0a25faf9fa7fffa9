#!/usr/bin/env bash
# Second README command: install what is missing, build everything, run the whole suite via ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh test
cmake --preset release
cmake --build --preset release
ctest --preset release "$@"
