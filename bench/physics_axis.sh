# Sourced by the benchmarks that need a commissioned physics axis (not a benchmark itself).
#
# commission_physics_axis EPA WORK NAME [FIRST_SEED=1]: the physics plant as a commissioning
# engineer identifies it, two 30 s `epa excite` runs to estimate and a third to validate (seeds
# FIRST_SEED, +1, +2), then `epa identify`; the model file is WORK/physics-model.toml. On a failure
# it prints identify's output under NAME and exits 1.
commission_physics_axis() {
  local epa=$1 work=$2 name=$3 first=${4:-1} i
  for i in 1 2 3; do "$epa" excite --plant physics --seed $((first + i - 1)) --duration 30 --out "$work/ex$i.csv" >/dev/null; done
  "$epa" identify "$work/ex1.csv" "$work/ex2.csv" --validate "$work/ex3.csv" --out "$work/physics-model.toml" >"$work/identify.log" 2>&1 ||
    { echo "$name: epa identify failed:" >&2; cat "$work/identify.log" >&2; exit 1; }
}
