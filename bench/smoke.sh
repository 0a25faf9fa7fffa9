#!/usr/bin/env bash
# CI's smoke step for the benchmarks: runs every benchmark under bench/ for about a second, as its
# header and the README say, on the current appliance, and checks that each one exits 0 and
# prints its result table. It checks that the scripts still work, not their figures (a second of
# load says nothing about throughput), so a benchmark can no longer rot unnoticed. The diagnosis
# benchmarks run their smoke mode, every step of the script on one case: diagnose_blind the blind
# set's breakpoints-out and one LuGre rig on 30-s excitations (its fast mode's eleven cases took
# 95 s of the stage), diagnose_drift the supply change (its fast cases are the release suite's
# diag.drift_fast).
#
#   bench/smoke.sh [BUILD_DIR=build/release]
#
# Installs the benchmarks' peers first (scripts/install-deps.sh bench: octave, rt-tests). Each
# benchmark's output goes to a log that is shown when it fails.
set -uo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
scripts/install-deps.sh bench || exit 1
cmake --build "$build" --target epa control_bench loop_jitter_bench modbus_load modbus_tls_load modbus_minimal_server arx_bench \
  diagnose_data health_drift >/dev/null || { echo "smoke: the benchmarks do not build" >&2; exit 1; }

logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT
passed=0
failed=0

# smoke NAME EXPECTED_LINE_REGEX COMMAND...: runs it, then looks for the line its table must have.
smoke() {
  local name=$1 expect=$2
  shift 2
  local log="$logs/$name.log" start=$SECONDS
  if "$@" >"$log" 2>&1 && grep -Eq "$expect" "$log"; then
    passed=$((passed + 1))
    echo "PASS: $name ($((SECONDS - start)) s)"
  else
    failed=$((failed + 1))
    echo "FAIL: $name ($*): exit status or the line /$expect/ missing; its output:" >&2
    tail -n 40 "$log" >&2
  fi
}

smoke control_bench 'BM_' "$build/bench/control_bench" --benchmark_min_time=0.01
smoke modbus_vs_peers '^8 client\(s\): epa / minimal throughput [0-9.]+' bench/modbus_vs_peers.sh 1
smoke modbus_tls_vs_plain '^tls/plain throughput: 8 clients [0-9.]+x' bench/modbus_tls_vs_plain.sh 1 10 1
smoke jitter_vs_cyclictest '^cyclictest wake-up +[0-9]' bench/jitter_vs_cyclictest.sh 1
smoke store_burst '^burst: 1000 Modbus writes' bench/store_burst.py 1 1
smoke arx_vs_octave '^speed ratio octave / ours: [0-9.]+x' bench/arx_vs_octave.sh "$build" 2000 2
smoke idle_memory '^VmRSS [0-9]+ kB' bench/idle_memory.sh 1
smoke attack '^attack: every row held' bench/attack.sh 1
smoke diagnose_bench '^epa diagnose, 9 runs x 20 s, all candidates: [0-9.]+ s wall' bench/diagnose_bench.sh "$build"
smoke pp_traj_tables '^pp-traj against its limits' bench/pp_traj_tables.sh "$build" fast
smoke health_drift '^health drift: [0-9]+ of [0-9]+ changes named' bench/health_drift.sh "$build" 1 40
smoke pp_traj_no_pass '^pp-traj no-pass: [0-9]+ moves' bench/pp_traj_no_pass.sh "$build" fast
smoke diagnose_blind '^physics friction score: [0-9]+/[0-9]+ cases correct' bench/diagnose_blind.sh smoke "$build"
smoke diagnose_drift '^score: [0-9]+/[0-9]+ cases correct' bench/diagnose_drift.sh smoke "$build"
smoke identify_physics '^identify_physics: [0-9]+ of [0-9]+ pairs' bench/identify_physics.sh "$build" 2 20
smoke commission_physics '^deployed [0-9]+/[0-9]+$' bench/commission_physics.sh 1 101 0.3 "$build"
smoke abuse_jitter '^abuse jitter p99 median: [0-9]+ us' bench/abuse_jitter.sh 1 1 "$build"
smoke health_jitter '^health jitter p99: on [0-9]+ us / off [0-9]+ us' bench/health_jitter.sh "$build" 1 3
smoke health_hil '^health hil: [0-9]+ of [0-9]+ changes named' bench/health_hil.sh "$build" 4 2 friction-x2

# Not in the "N passed, N failed" form: the suite's count is ctest's, these are not tests.
if [ "$failed" -eq 0 ]; then echo "bench smoke: all $passed benchmarks ran"; else echo "bench smoke: $failed of $((passed + failed)) benchmarks FAILED"; exit 1; fi
