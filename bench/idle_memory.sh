#!/usr/bin/env bash
# The appliance's idle memory: `epa serve` as config/epa.toml ships it (sim plant, memory locking
# on, Modbus and the status page on free loopback ports), left alone for SECONDS, then VmRSS,
# VmLck and the thread count from /proc/PID/status. Goal: VmRSS <= 64 MB with locking on.
#
#   bench/idle_memory.sh [SECONDS=5]     (run as root, or memory is not locked and the figure flatters)
#
# Loopback only; the appliance is stopped by its PID.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
seconds=${1:-5}
[[ $seconds =~ ^[0-9]+([.][0-9]+)?$ ]] || { echo "usage: $0 [seconds]" >&2; exit 1; }
[[ $EUID -eq 0 ]] || echo "warning: not root: memory is not locked, so VmRSS is lower than deployed" >&2
cmake --build --preset release --target epa >/dev/null
work=$(mktemp -d)
pid=""
cleanup() {
  if [[ -n $pid ]]; then kill -TERM "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT
free_port() { /usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
sed -e "s|^address = \"0.0.0.0\"|address = \"127.0.0.1\"|" \
    -e "0,/^port = 502/s||port = $(free_port)|" -e "0,/^port = 8080/s||port = $(free_port)|" \
    -e "s|\"../registers/epa.csv\"|\"$repo/registers/epa.csv\"|" -e "s|static_dir = \"../web\"|static_dir = \"$repo/web\"|" \
    -e "s|^path = \"epa.db\"|path = \"$work/epa.db\"|" -e "s|^directory = \"runs\"|directory = \"$work/runs\"|" \
    config/epa.toml > "$work/epa.toml"
build/release/src/app/epa serve --config "$work/epa.toml" > "$work/epa.log" 2>&1 &
pid=$!
sleep "$seconds"
kill -0 "$pid" 2>/dev/null || { echo "the appliance exited:" >&2; cat "$work/epa.log" >&2; exit 1; }
rss_kb=$(awk '/^VmRSS:/ {print $2}' /proc/$pid/status)
lck_kb=$(awk '/^VmLck:/ {print $2}' /proc/$pid/status)
threads=$(awk '/^Threads:/ {print $2}' /proc/$pid/status)
grep -q "memory not locked" "$work/epa.log" && locked="no (see the log)" || locked="yes"
echo "epa serve idle for ${seconds} s (config/epa.toml, memory locking asked: $locked)"
echo "VmRSS ${rss_kb} kB ($((rss_kb / 1024)) MB), VmLck ${lck_kb} kB (locked on touch), threads ${threads}; goal VmRSS <= 64 MB"
