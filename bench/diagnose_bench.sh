#!/bin/sh
# Times `epa diagnose` on 9 runs of 20 s (6 training, 3 held out) with all eight candidates, on
# data with a valve lag hidden in the simulator. Usage: bench/diagnose_bench.sh BUILD_DIR
set -eu
build=${1:-build/release}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
keep=${KEEP:-}  # KEEP=folder: leave the JSON and HTML report there
"$build/bench/diagnose_data" "$dir" "${EFFECT:-valve_lag}" 9 20
start=$(date +%s%N)
"$build/src/app/epa" diagnose "$dir/run-1.csv" "$dir/run-2.csv" "$dir/run-3.csv" "$dir/run-4.csv" "$dir/run-5.csv" \
  "$dir/run-6.csv" --holdout "$dir/run-7.csv" "$dir/run-8.csv" "$dir/run-9.csv" --json "$dir/gap.json" --report "$dir/gap.html"
end=$(date +%s%N)
[ -z "$keep" ] || cp "$dir/gap.json" "$dir/gap.html" "$keep"/
ms=$(( (end - start) / 1000000 ))
echo "epa diagnose, 9 runs x 20 s, all candidates: $((ms / 1000)).$(printf %03d $((ms % 1000))) s wall"
