#!/usr/bin/env bash
# The identification figures of docs/identification.md: `epa identify` on open-loop runs of the
# physics plant (defaults, supply 4.8 bar, spool overlap 0.2 V wider each way, friction 1.5x and
# 0.5x of the defaults' static / sliding 40 / 25 N), every ordered pair of seeds
# (estimation run i, validation run j), the Hammerstein model's and the stick-slip model's
# validation free-run fits and the stick-slip model's ramp starts. The plant's own ramp starts
# (the truth for the break points) come from ident_physics_test, which measures them on the plant.
#
#   bench/identify_physics.sh [BUILD_DIR=build/release] [SEEDS=3] [DURATION_S=90]
#
# CI's smoke step runs it with 2 seeds of 20 s.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
seeds=${2:-3}
duration=${3:-90}
epa="$build/src/app/epa"
[ -x "$epa" ] || { echo "identify_physics: $epa is not built" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

defaults=config/pneumatic-plant.toml
cp "$defaults" "$work/defaults.toml"
sed 's/^supply_pressure_bar *=.*/supply_pressure_bar = 4.8/' "$defaults" >"$work/supply-4.8bar.toml"
sed -e 's/^overlap_pos_v *=.*/overlap_pos_v = 1.4/' -e 's/^overlap_neg_v *=.*/overlap_neg_v = -1.9/' "$defaults" >"$work/overlap+0.2V.toml"
sed -e 's/^static_friction_n *=.*/static_friction_n = 60.0/' -e 's/^coulomb_friction_n *=.*/coulomb_friction_n = 37.5/' "$defaults" >"$work/friction-x1.5.toml"
sed -e 's/^static_friction_n *=.*/static_friction_n = 20.0/' -e 's/^coulomb_friction_n *=.*/coulomb_friction_n = 12.5/' "$defaults" >"$work/friction-x0.5.toml"
plants=(defaults supply-4.8bar overlap+0.2V friction-x1.5 friction-x0.5)
for plant in "${plants[@]}"; do
  grep -q . "$work/$plant.toml" || { echo "identify_physics: no $plant parameters" >&2; exit 1; }
done
cmp -s "$work/defaults.toml" "$work/supply-4.8bar.toml" && { echo "identify_physics: supply_pressure_bar not found in $defaults" >&2; exit 1; }
cmp -s "$work/defaults.toml" "$work/overlap+0.2V.toml" && { echo "identify_physics: overlap keys not found in $defaults" >&2; exit 1; }
cmp -s "$work/defaults.toml" "$work/friction-x1.5.toml" && { echo "identify_physics: friction keys not found in $defaults" >&2; exit 1; }

echo "| plant | estimation / validation seed | Hammerstein validation fit | stick-slip validation fit | stick-slip ramp starts (0.1 V/s) | seconds |"
echo "| --- | --- | --- | --- | --- | --- |"
all=()
for plant in "${plants[@]}"; do
  for s in $(seq 1 "$seeds"); do
    "$epa" excite --plant physics --physics-config "$work/$plant.toml" --duration "$duration" --seed "$s" \
      --out "$work/$plant-$s.csv" >/dev/null
  done
  fits=()
  for e in $(seq 1 "$seeds"); do
    for v in $(seq 1 "$seeds"); do
      [ "$e" = "$v" ] && continue
      start=$EPOCHREALTIME
      "$epa" identify "$work/$plant-$e.csv" --validate "$work/$plant-$v.csv" >"$work/id.log" 2>&1 ||
        { echo "identify_physics: epa identify failed on $plant $e/$v:" >&2; tail -n 5 "$work/id.log" >&2; exit 1; }
      took=$(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN {print b - a}')
      line=$(grep -E '^  free-run fit: estimation .* validation' "$work/id.log") ||
        { echo "identify_physics: no stick-slip fit line in the output of $plant $e/$v" >&2; exit 1; }
      ramps=$(grep -oE 'starts to move at [^ ]+ / [^ ]+ V' "$work/id.log" | sed 's/starts to move at //')
      stick=$(echo "$line" | sed -E 's/.*validation ([0-9.-]+) %.*/\1/')
      hamm=$(echo "$line" | sed -E 's/.*Hammerstein model: [0-9.-]+ %, ([0-9.-]+) %.*/\1/')
      printf '| %s | %s / %s | %s %% | %s %% | %s | %.1f |\n' "$plant" "$e" "$v" "$hamm" "$stick" "$ramps" "$took"
      fits+=("$stick")
      all+=("$stick")
    done
  done
  printf '%s\n' "${fits[@]}" | sort -n | awk -v p="$plant" '{a[NR]=$1} END {m=(NR%2)?a[(NR+1)/2]:(a[NR/2]+a[NR/2+1])/2;
    n=0; for(i=1;i<=NR;i++) if(a[i]>=90) n++; printf "%s: stick-slip validation fit min %.2f %%, median %.2f %%, %d of %d pairs >= 90 %%\n", p, a[1], m, n, NR}' >>"$work/summary"
done
echo
cat "$work/summary"
printf '%s\n' "${all[@]}" | sort -n | awk '{a[NR]=$1} END {n=0; for(i=1;i<=NR;i++) if(a[i]>=90) n++;
  printf "identify_physics: %d of %d pairs >= 90 %%, worst %.2f %%\n", n, NR, a[1]}'
