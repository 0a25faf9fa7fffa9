#!/usr/bin/env python3
"""Blind friction rigs on the physics plant: Karnopp (the plant's stick test with its Stribeck
curve) and LuGre bristles (no hard stick: presliding, then sliding), each at two levels, and an
axis with almost no friction. Each rig is commissioned as a user would (two `epa excite` runs of
90 s, `epa identify`), then FF-IDZ and NG-IDZ steps and an excitation are recorded (6 training,
3 held-out runs) and diagnosed against the model file. The stick-slip model that identify fits
knows neither form: Coulomb friction with a breakaway, on an air spring.

    physics_friction_rigs.py EPA_BINARY [--fast] [--seeds N] [--excite-seconds S] [--keep DIR]

A friction rig is correct when `static_friction` is named and `unexplained` is false; the
near-frictionless one when `static_friction` is not named (naming it is false blame). Prints one
line per case and the score line:

    physics friction score: C/N cases correct, false_blame_on_null=F/M, median_reduction_pct=R
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "drift"))
import drift_benchmark as db  # noqa: E402  (its physics-config writer and runner)

MASS_KG = 1.5  # config/pneumatic-plant.toml's piston_mass_kg
SIGMA0 = 1e5   # N/m: a presliding distance of tenths of a mm at the default friction


def friction(scale, lugre=False):
    t = {"static_friction_n": 40.0 * scale, "coulomb_friction_n": 25.0 * scale}
    if lugre:
        t["lugre_stiffness_n_per_m"] = SIGMA0
        t["lugre_damping_n_s_per_m"] = 2.0 * (SIGMA0 * MASS_KG) ** 0.5
    return {"friction": t}


# name, category, physics-config tables
CASES = [
    ("karnopp-default", "friction", friction(1.0)),
    ("karnopp-x1.5", "friction", friction(1.5)),
    ("lugre-default", "friction", friction(1.0, lugre=True)),
    ("lugre-x1.5", "friction", friction(1.5, lugre=True)),
    ("nearly-frictionless", "null", friction(0.1)),
]
FAST = {"lugre-default"}


def rig(epa, folder, tables, seed, excite_s=90):
    config = os.path.join(folder, "plant.toml")
    db.write_physics_config(config, tables)
    for k in (1, 2):
        db.run([epa, "excite", "--plant", "physics", "--physics-config", config, "--seed", str(10 * seed + k),
                "--duration", str(excite_s), "--out", f"{folder}/ex{k}.csv"])
    db.run([epa, "identify", f"{folder}/ex1.csv", "--validate", f"{folder}/ex2.csv", "--out", f"{folder}/model.toml"])
    for steps, start, out, s in (("40,120", "150", "tr", 3), ("-60,-150", "350", "tr", 4), ("75,-90", "250", "ho", 5)):
        db.run([epa, "simulate", "--plant", "physics", "--physics-config", config, "--model", f"{folder}/model.toml",
                "--controller", "pp-ffidz", "pp-ngidz", "--steps", steps, "--start", start, "--duration", "6", "--noise", "0.1",
                "--seed", str(100 * seed + s), "--out-dir", f"{folder}/{out}"])
    train = sorted(f"{folder}/tr/{f}" for f in os.listdir(f"{folder}/tr")) + [f"{folder}/ex1.csv"]
    held = sorted(f"{folder}/ho/{f}" for f in os.listdir(f"{folder}/ho")) + [f"{folder}/ex2.csv"]
    return train, held


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("epa")
    ap.add_argument("--fast", action="store_true", help="one LuGre rig, one seed")
    ap.add_argument("--excite-seconds", type=int, default=90,
                    help="the commissioning's two excitations (CI's smoke step: 30, the script's path, not its figure)")
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--keep", help="leave each rig's runs and report here")
    args = ap.parse_args()
    cases = [c for c in CASES if not args.fast or c[0] in FAST]
    seeds = range(1, 2 if args.fast else args.seeds + 1)
    results = []
    with tempfile.TemporaryDirectory(prefix="epa-physics-friction-") as tmp:
        for seed in seeds:
            for name, category, tables in cases:
                folder = os.path.join(args.keep or tmp, f"{name}-s{seed}")
                os.makedirs(folder, exist_ok=True)
                train, held = rig(args.epa, folder, tables, seed, args.excite_seconds)
                out = os.path.join(folder, "gap.json")
                r = subprocess.run([args.epa, "diagnose", *train, "--holdout", *held, "--model", f"{folder}/model.toml",
                                    "--json", out], capture_output=True, text=True, timeout=600)
                if r.returncode != 0:
                    print(f"FAIL {name} s{seed}: epa diagnose failed: {r.stderr.strip()[-400:]}")
                    results.append((name, category, set(), True, 0.0, False))
                    continue
                v = json.load(open(out))["verdict"]
                named, unexplained = set(v["effects"]), bool(v["unexplained"])
                ok = ("static_friction" not in named) if category == "null" else ("static_friction" in named and not unexplained)
                results.append((name, category, named, unexplained, float(v["reduction_pct"]), ok))
                print(f"{'ok  ' if ok else 'MISS'} {name:20s} s{seed} named={sorted(named)} unexplained={unexplained} "
                      f"reduction={v['reduction_pct']:.0f}% on {v.get('measure', '?')}", flush=True)
    correct = sum(r[5] for r in results)
    nulls = [r for r in results if r[1] == "null"]
    blamed = sum(1 for r in nulls if "static_friction" in r[2])
    scored = [r[4] for r in results if r[1] == "friction"]
    print(f"physics friction score: {correct}/{len(results)} cases correct, false_blame_on_null={blamed}/{len(nulls)}, "
          f"median_reduction_pct={statistics.median(scored) if scored else 0.0:.1f}")


if __name__ == "__main__":
    main()
