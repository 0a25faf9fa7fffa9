#!/bin/sh
# The physics rig as a commissioning engineer meets it: two excitation runs, epa identify, closed-
# loop steps with FF-IDZ and NG-IDZ, then epa diagnose against the model file. The diagnosis must
# name static_friction over whole moves, explain at least 70 % of the law's model's gap there, and
# give the same verdict at --horizon 20 and 100 (the windowed gap's horizon does not judge it).
# Under the sanitizers (EPA_SANITIZER_RUN=1, the asan test preset) the diagnosis runs at --horizon
# 20 alone and is judged as above: the run at 100 takes the same paths over longer windows (about
# 60 % of the test's time), and that the horizon does not change the verdict is the release run's.
#   physics_rig_test.sh EPA_BINARY
set -eu
epa=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir"
"$epa" excite --plant physics --seed 1 --duration 90 --out ex1.csv >/dev/null
"$epa" excite --plant physics --seed 2 --duration 90 --out ex2.csv >/dev/null
"$epa" identify ex1.csv --validate ex2.csv --out model.toml >/dev/null 2>&1
sim() { "$epa" simulate --plant physics --model model.toml --controller pp-ffidz pp-ngidz --duration 6 --noise 0.1 "$@" >/dev/null; }
sim --steps 40,120 --start 150 --seed 3 --out-dir tr
sim --steps -60,-150 --start 350 --seed 4 --out-dir tr
sim --steps 75,-90 --start 250 --seed 5 --out-dir ho
horizons="20 100"
[ "${EPA_SANITIZER_RUN:-}" = 1 ] && horizons=20
for h in $horizons; do
  "$epa" diagnose tr/*.csv ex1.csv --holdout ho/*.csv ex2.csv --model model.toml --horizon $h --json gap$h.json >/dev/null 2>&1
done
python3 - $horizons <<'PY'
import json, sys
v = [json.load(open(f"gap{h}.json"))["verdict"] for h in sys.argv[1:]]
print("; ".join(f"horizon {h}: {x['effects']} {x['reduction_pct']} % on {x['measure']}" for h, x in zip(sys.argv[1:], v)))
v20 = v[0]
ok = ("static_friction" in v20["effects"] and v20["measure"] == "whole_move" and v20["reduction_pct"] >= 70.0
      and not v20["unexplained"] and all((x["effects"], x["reduction_pct"], x["unexplained"]) ==
                                         (v20["effects"], v20["reduction_pct"], v20["unexplained"]) for x in v))
sys.exit(0 if ok else 1)
PY
