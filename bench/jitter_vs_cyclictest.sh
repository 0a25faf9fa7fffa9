#!/usr/bin/env bash
# The scan cycle's timing next to cyclictest (Debian rt-tests), on the same machine in the same
# script, one after the other so they do not disturb each other: both at 1 kHz, SCHED_FIFO 80,
# memory locked, for the same time. Prints a table and the ratio of the p99 wake-up latencies
# (goal: the loop within 1.5x of cyclictest).
# Usage: bench/jitter_vs_cyclictest.sh [seconds]   (default 60; needs root for SCHED_FIFO)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
scripts/install-deps.sh bench  # cyclictest (rt-tests)
cmake --build --preset release --target loop_jitter_bench >/dev/null
out=$(mktemp -d)

build/release/bench/loop_jitter_bench --period-us 1000 --seconds "$seconds" --priority 80 > "$out/loop.json"
cyclictest --mlockall --priority=80 --interval=1000 --loops=$((seconds * 1000)) --quiet --histogram=5000 > "$out/cyclictest.txt"

python3 - "$out/loop.json" "$out/cyclictest.txt" <<'PY'
import json, sys
loop = json.load(open(sys.argv[1]))
# cyclictest --histogram: "us count" rows, then "# Max Latencies: ..." etc.
counts = {}
for line in open(sys.argv[2]):
    parts = line.split()
    if len(parts) == 2 and parts[0].isdigit():
        counts[int(parts[0])] = int(parts[1])
    if line.startswith("# Max Latencies"):
        ct_max = int(line.split(":")[1].split()[0])
total = sum(counts.values())
def pct(p):
    seen, want = 0, p * total
    for us in sorted(counts):
        seen += counts[us]
        if seen >= want and seen > 0:
            return us + 1  # upper edge of the 1 us bin, as the loop reports it
    return ct_max
ct = {"p50": pct(0.50), "p99": pct(0.99), "max": ct_max}
print(f"{'':28}{'p50 (us)':>10}{'p99 (us)':>10}{'max (us)':>10}")
print(f"{'epa scan cycle wake-up':28}{loop['wake_p50_us']:>10.0f}{loop['wake_p99_us']:>10.0f}{loop['wake_max_us']:>10.0f}")
print(f"{'cyclictest wake-up':28}{ct['p50']:>10.0f}{ct['p99']:>10.0f}{ct['max']:>10.0f}")
print(f"{'epa period jitter':28}{loop['jitter_p50_us']:>10.0f}{loop['jitter_p99_us']:>10.0f}{loop['jitter_max_us']:>10.0f}")
print(f"{'epa compute time':28}{loop['compute_p50_us']:>10.0f}{loop['compute_p99_us']:>10.0f}{loop['compute_max_us']:>10.0f}")
print(f"cycles {loop['cycles']}, overruns {loop['overruns']}, moves {loop['moves']}; cyclictest samples {total}")
print(f"p99 wake-up ratio epa / cyclictest: {loop['wake_p99_us'] / max(ct['p99'], 1):.2f} (goal <= 1.5)")
PY
rm -rf "$out"
