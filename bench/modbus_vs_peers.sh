#!/usr/bin/env bash
# The appliance's Modbus TCP server next to its peers, in one script: throughput and latency of
# reading 10 holding registers (FC3, addresses 0-9: setpoint .. unlock, all mapped) with 1 and 8
# clients (bench/modbus_load, libmodbus clients in a closed loop, 1 s warm-up, then T seconds)
# against
#   epa      the appliance (epa serve, sim plant, RUN at 100 mm, loop at SCHED_FIFO 80 with memory
#            locked and the PM QoS request, as config/epa.toml ships; max_clients_per_address
#            lifted to 16, as the load generator is one host)
#   minimal  bench/modbus_minimal_server: libmodbus' own multi-client pattern, the ceiling for a
#            libmodbus-based server
#   pymodbus bench/pymodbus_server.py: pymodbus 3.0's asyncio server (Debian python3-pymodbus)
# and, for the appliance, the scan cycle's p99 wake-up latency and period jitter idle and under
# each load, read from its own input registers (loop_wake_p99_us 92, loop_jitter_p99_us 96). The
# loop's histograms count from start-up, so every measurement gets a fresh appliance that runs
# the same 1 + T seconds, idle or loaded.
#
# Usage: bench/modbus_vs_peers.sh [seconds]   (default 10; run as root for SCHED_FIFO)
# Environment: PIN_CPU=<taskset cpu list> pins every server and the load generator to those
#   CPUs (default: the last CPU, so client and server share one core and no run depends on
#   where the scheduler put them: on a VM a cross-core wake-up costs tens of microseconds and
#   turns 46,000 req/s into 12,000-16,000). The appliance's SCHED_FIFO scan-cycle thread is
#   given all CPUs back, as deployed (the scheduler places it; pinned to the benchmark's CPU its
#   idle p99 jitter varied 27-174 us between runs). PIN_CPU=none leaves placement to the scheduler.
# Loopback only; every process is started here and stopped by its PID, also on Ctrl-C.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
seconds=${1:-10}
[[ $seconds =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "usage: $0 [seconds]" >&2; exit 1; }
warmup=1
py=/usr/bin/python3  # Debian's interpreter: python3-pymodbus lives there
"$py" -c 'import pymodbus.server' 2>/dev/null ||
  { echo "pymodbus 3.0 missing: run scripts/install-deps.sh" >&2; exit 1; }
command -v taskset >/dev/null && command -v chrt >/dev/null || { echo "taskset, chrt missing: run scripts/install-deps.sh" >&2; exit 1; }
[[ $EUID -eq 0 ]] || echo "warning: not root: the appliance's loop runs without SCHED_FIFO and memory locking" >&2

source bench/cpu_pinning.sh  # pin_cpu, pin, online_cpus, unpin_scan_cycle

cmake --build --preset release --target epa modbus_load modbus_minimal_server >/dev/null
epa=build/release/src/app/epa
load=build/release/bench/modbus_load
minimal=build/release/bench/modbus_minimal_server

out=$(mktemp -d)
server_pid=""

# Stops the running server by its PID: SIGTERM, up to 5 s to exit, then SIGKILL.
stop_server() {
  [[ -n $server_pid ]] || return 0
  kill -TERM "$server_pid" 2>/dev/null || true
  for _ in $(seq 50); do
    kill -0 "$server_pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -KILL "$server_pid" 2>/dev/null || true
  wait "$server_pid" 2>/dev/null || true
  server_pid=""
}
cleanup() {
  stop_server
  rm -rf "$out"
}
trap cleanup EXIT
trap 'echo "interrupted" >&2; exit 130' INT TERM

free_port() {
  "$py" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# start_server KIND PORT LOG: starts it in the background (server_pid), waits until it answers a
# read (at most 15 s) or exits with its log.
start_server() {
  local kind=$1 port=$2 log=$3
  case $kind in
    epa)
      cat > "$out/epa.toml" <<EOF
[loop]
realtime_priority = 80
lock_memory = true
cpu_dma_latency_us = 0
[recorder]
directory = "$out/runs"
[store]
path = "$out/epa.db"
[log]
status_interval_s = 0
[modbus]
address = "127.0.0.1"
port = $port
max_clients_per_address = 16
register_map = "$repo/registers/epa.csv"
[web]
address = "127.0.0.1"
port = $(free_port)
static_dir = "$repo/web"
[hal]
backend = "sim"
EOF
      "${pin[@]}" "$epa" serve --config "$out/epa.toml" --mode run --setpoint 100 > "$log" 2>&1 &
      ;;
    minimal) "${pin[@]}" "$minimal" --port "$port" > "$log" 2>&1 & ;;
    pymodbus) "${pin[@]}" "$py" bench/pymodbus_server.py --port "$port" > "$log" 2>&1 & ;;
  esac
  server_pid=$!
  if ! "$load" --port "$port" --address 0 --count 10 --wait-ready 15 --seconds 0 2>> "$log" || ! kill -0 "$server_pid" 2>/dev/null; then
    echo "$kind server did not come up on port $port:" >&2
    tail -n 20 "$log" >&2
    exit 1
  fi
  if [[ $kind == epa ]]; then unpin_scan_cycle "$server_pid"; fi
}

# The scan cycle's statistics as JSON, read from the appliance's input registers (float32 ABCD).
read_loop_stats() {
  "$load" --port "$1" --read-float-input 90 --read-float-input 92 --read-float-input 94 --read-float-input 96 --read-float-input 98
}

for kind in epa minimal pymodbus; do
  for clients in 1 8; do
    port=$(free_port)
    echo "$kind, $clients client(s), port $port, ${warmup} s + ${seconds} s ..." >&2
    start_server "$kind" "$port" "$out/$kind-$clients.log"
    "${pin[@]}" "$load" --port "$port" --address 0 --count 10 --unit 1 --clients "$clients" \
      --warmup "$warmup" --seconds "$seconds" > "$out/$kind-$clients.json" ||
      echo "warning: no successful request against $kind with $clients client(s)" >&2
    if [[ $kind == epa ]]; then read_loop_stats "$port" > "$out/loop-$clients.json"; fi
    stop_server
  done
done
# The same appliance idle for as long: start-up, readiness probe, 1 + T seconds, read.
port=$(free_port)
echo "epa idle, port $port, ${warmup} s + ${seconds} s ..." >&2
start_server epa "$port" "$out/epa-idle.log"
sleep "$(awk -v a="$warmup" -v b="$seconds" 'BEGIN { print a + b }')"
read_loop_stats "$port" > "$out/loop-idle.json"
stop_server

"$py" - "$out" "$seconds" "$pin_cpu" <<'PY'
import json, sys
out, seconds, pin = sys.argv[1], sys.argv[2], sys.argv[3]
load = {(k, n): json.load(open(f"{out}/{k}-{n}.json")) for k in ("epa", "minimal", "pymodbus") for n in (1, 8)}
loop = {c: json.load(open(f"{out}/loop-{c}.json")) for c in ("idle", 1, 8)}
fmt = lambda v, f="{:.0f}": "-" if v is None else f.format(v)
print(f"\nModbus TCP, FC3 10 holding registers, {seconds} s per run after 1 s warm-up, "
      f"{'CPUs ' + pin if pin != 'none' else 'not pinned'}")
print(f"{'server':10}{'clients':>8}{'req/s':>10}{'p50 us':>9}{'p99 us':>9}{'max us':>9}{'errors':>8}")
for (k, n), r in load.items():
    print(f"{k:10}{n:>8}{fmt(r['throughput_rps']):>10}{fmt(r['p50_us']):>9}{fmt(r['p99_us']):>9}"
          f"{fmt(r['max_us']):>9}{r['errors']:>8}")
ratio = lambda a, b: "-" if not a or not b else f"{a / b:.2f}"
for n in (1, 8):
    e, m, p = load[("epa", n)], load[("minimal", n)], load[("pymodbus", n)]
    print(f"{n} client(s): epa / minimal throughput {ratio(e['throughput_rps'], m['throughput_rps'])} (goal >= 1.0), "
          f"epa / pymodbus {ratio(e['throughput_rps'], p['throughput_rps'])}"
          + (f"; epa p99 {fmt(e['p99_us'])} us (goal < 1000)" if n == 8 else ""))
print(f"\nScan cycle (5 ms, SCHED_FIFO 80), fresh appliance per column, {seconds} s + 1 s each")
cols = [("idle", "idle"), (1, "1 client"), (8, "8 clients")]
print(f"{'':26}" + "".join(f"{name:>11}" for _, name in cols) + f"{'1 / idle':>10}{'8 / idle':>10}")
for reg, name in (("input_90", "wake-up p50 (us)"), ("input_92", "wake-up p99 (us)"), ("input_94", "wake-up max (us)"),
                  ("input_96", "period jitter p99 (us)"), ("input_98", "compute p99 (us)")):
    idle = loop["idle"][reg]
    ratios = "".join(f"{loop[c][reg] / idle:>10.2f}" if idle > 0 else f"{'-':>10}" for c in (1, 8))
    print(f"{name:26}" + "".join(f"{loop[c][reg]:>11.1f}" for c, _ in cols) + ratios)
print("goal: loaded p99 jitter within 1.2x of idle")
PY
