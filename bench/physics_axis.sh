# Sourced by the benchmarks that need a commissioned physics axis (not a benchmark itself).
#
# commission_physics_axis EPA WORK NAME: the physics plant as a commissioning engineer identifies
# it, two 30 s `epa excite` runs to estimate and a third to validate, then `epa identify`; the
# model file is WORK/physics-model.toml. On a failure it prints identify's output under NAME and
# exits 1.
commission_physics_axis() {
  local epa=$1 work=$2 name=$3 seed
  for seed in 1 2 3; do "$epa" excite --plant physics --seed "$seed" --duration 30 --out "$work/ex$seed.csv" >/dev/null; done
  "$epa" identify "$work/ex1.csv" "$work/ex2.csv" --validate "$work/ex3.csv" --out "$work/physics-model.toml" >"$work/identify.log" 2>&1 ||
    { echo "$name: epa identify failed:" >&2; cat "$work/identify.log" >&2; exit 1; }
}
