#!/usr/bin/env bash
# Installs the Debian 12 packages the project builds, tests, runs and benchmarks with, and (for the
# tests) the node modules of tests/interop/node (npm ci from its package-lock.json). Idempotent:
# it only calls apt-get (and npm) when something is missing, so repeated runs cost nothing.
#
#   scripts/install-deps.sh          # build and run (scripts/run.sh); the test suite's Debian packages too
#   scripts/install-deps.sh test     # and the node modules of the modbus-serial interop test (scripts/test.sh)
#   scripts/install-deps.sh bench    # and what the benchmarks compare against (bench/, CI's smoke step)
#
# Every program a script, test or benchmark calls is named here, even the ones a minimal Debian
# usually has, so nothing is assumed from the machine (a fresh debootstrap root has no curl and
# no python3). A test that needs a program checks for it and fails naming this script.
set -euo pipefail

packages=(
  # build
  build-essential cmake ninja-build ccache pkg-config
  libeigen3-dev libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libjs-chart.js libpagmo-dev libnlopt-cxx-dev libsqlite3-dev
  libmodbus-dev libcomedi-dev libspdlog-dev libsystemd-dev libcpp-httplib-dev libssl-dev
  # sanitizer and fuzz builds (scripts/test-sanitizers.sh, test-tsan.sh, fuzz.sh)
  clang libclang-rt-14-dev
  # programs the tests and scripts call: Modbus clients (mbpoll, Debian's python3 with pymodbus),
  # the browser and its certificate database (certutil: the CA trusted as a user imports it),
  # HTTP (curl), TLS (openssl s_client), taskset/chrt (util-linux), mount (fault injection), promtool
  # (/metrics checked by Prometheus' own linter; Debian ships it only in prometheus, which also
  # installs the Prometheus server as a service: the tests use promtool alone); sqlite3 is the
  # database's own shell, for looking into the tuning store (epa.db)
  python3 python3-pymodbus python3-serial-asyncio mbpoll chromium libnss3-tools curl sqlite3 util-linux mount prometheus openssl
  # Node.js and npm: the modbus-serial interop test (tests/interop/node, its modules by `npm ci` below)
  nodejs npm
)
bench_packages=(
  # bench/jitter_vs_cyclictest.sh: cyclictest is the scan cycle's timing peer
  rt-tests
  # bench/arx_vs_octave.sh: GNU Octave's control package is the ARX peer
  octave octave-control
)

node_modules=no
case "${1:-}" in
  "") ;;
  test) node_modules=yes ;;
  bench) packages+=("${bench_packages[@]}"); node_modules=yes ;;
  *) echo "usage: $0 [test|bench]" >&2; exit 2 ;;
esac

missing=()
for p in "${packages[@]}"; do
  # A nodejs from elsewhere (NodeSource's) bundles npm and conflicts with Debian's npm package:
  # the commands on PATH count as installed.
  case "$p" in nodejs) command -v node >/dev/null && continue ;; npm) command -v npm >/dev/null && continue ;; esac
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
    sudo="sudo"
  fi
  echo "install-deps: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# The modbus-serial interop test's node modules, exactly as package-lock.json pins them (from the npm
# registry); again only when they are missing or older than the lockfile. The one thing not from
# Debian's mirror: when the registry cannot be reached (no route, or a TLS-intercepting proxy whose
# CA npm does not know) that one test is reported as skipped, with this reason, and the rest runs.
node_dir="$(cd "$(dirname "$0")/.." && pwd)/tests/interop/node"
if [ "$node_modules" = yes ] && [ ! "$node_dir/node_modules/.package-lock.json" -nt "$node_dir/package-lock.json" ]; then
  echo "install-deps: npm ci in $node_dir"
  if ! (cd "$node_dir" && npm ci --no-audit --no-fund); then
    rm -rf "$node_dir/node_modules"
    echo "install-deps: WARNING: npm ci failed (its error is above): the npm registry was not reachable." \
         "Only interop.modbus_serial needs it; ctest reports it as skipped. Behind a proxy with its own CA:" \
         "npm config set cafile /path/to/ca.pem, then run scripts/install-deps.sh test again." >&2
  fi
fi
