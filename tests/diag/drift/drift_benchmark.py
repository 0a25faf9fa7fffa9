#!/usr/bin/env python3
"""Drift benchmark of `epa diagnose` on the physics plant: an axis is commissioned (two `epa
excite` runs, then `epa identify`), then one physical parameter of the plant changes at a time
(friction, supply, spool, valve overlap, a line, the sensor, a leak), or two, or none. Each case
is recorded as an engineer would (closed-loop steps with the commissioned law, open-loop ramps and
pulse trains: 6 training and 3 held-out runs) and diagnosed against the commissioned model file.

    drift_benchmark.py EPA_BINARY [--fast] [--keep DIR] [--matrix FILE] [--check] [--only REGEX]

The diagnosis answers "what changed since commissioning" in the report's `verdict.changes` (the
names of the changed parts of the commissioned model) and `verdict.changes_unexplained`. A case is
correct when every expected change is named, nothing outside it and its allowed companions is
named, and the change is not called unexplained; a null (the same plant, new noise and new
targets) when nothing is named and nothing is unexplained; the leak, outside the model's terms,
when it is called unexplained and nothing is blamed. Prints one line per case, the confusion
matrix and the score line:

    score: C/N cases correct, false_blame_on_null=F/M, median_reduction_pct=R, median_seconds=S

--check exits 1 unless the issue's thresholds hold (>= 90 % correct, no false blame on the nulls,
median reduction >= 70 %, median <= 10 s per case). --guard exits 1 when a diagnosis failed or a
null was blamed: what a change must never break (ctest diag.drift_fast). Under the sanitizers
(EPA_SANITIZER_RUN=1, the asan test preset) --fast leaves out friction-x2.5: the supply change and
the null are diagnosed and guarded, and a third diagnosis of a changed axis takes their paths again.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from confusion_table import confusion_table  # noqa: E402

NAMES = ["gain_change", "deadzone_shift", "input_delay", "valve_lag", "static_friction", "sensor_quantization"]
TIMING = {"input_delay", "valve_lag"}  # a spool lag and a line delay are confusable: either may come beside the other

# The defaults of config/pneumatic-plant.toml: the commissioned axis.
FRICTION = {"static_friction_n": 40.0, "coulomb_friction_n": 25.0}
SPOOL_S = 0.005
OVERLAP = (1.2, -1.7)


def friction(scale):
    return {"friction": {k: v * scale for k, v in FRICTION.items()}}


def overlap_worn(v):
    return {"valve": {"overlap_pos_v": OVERLAP[0] - v, "overlap_neg_v": OVERLAP[1] + v}}


def merge(*tables):
    out = {}
    for t in tables:
        for table, keys in t.items():
            out.setdefault(table, {}).update(keys)
    return out


# name, category, physics-config tables, {sensor_bits, delay_samples}, expected changes, allowed companions
CASES = [
    ("friction-x1.6", "friction", friction(1.6), {}, {"static_friction"}, set()),
    ("friction-x2.5", "friction", friction(2.5), {}, {"static_friction"}, set()),
    ("supply-4.5bar", "supply", {"supply": {"supply_pressure_bar": 4.5}}, {}, {"gain_change"}, set()),
    ("supply-4bar", "supply", {"supply": {"supply_pressure_bar": 4.0}}, {}, {"gain_change"}, set()),
    ("spool-div3", "spool", {"valve": {"spool_time_constant_s": SPOOL_S * 3}}, {}, {"valve_lag"}, TIMING),
    ("spool-div5", "spool", {"valve": {"spool_time_constant_s": SPOOL_S * 5}}, {}, {"valve_lag"}, TIMING),
    ("overlap-worn-0.2V", "overlap", overlap_worn(0.2), {}, {"deadzone_shift"}, set()),
    ("overlap-worn-0.3V", "overlap", overlap_worn(0.3), {}, {"deadzone_shift"}, set()),
    ("line-10ms", "line", {}, {"delay_samples": 2}, {"input_delay"}, TIMING),
    ("line-20ms", "line", {}, {"delay_samples": 4}, {"input_delay"}, TIMING),
    ("sensor-10bit", "sensor", {}, {"sensor_bits": 10}, {"sensor_quantization"}, set()),
    ("leak-A", "leak", {"cylinder": {"leak_a_mm2": 0.05}}, {}, set(), set()),
    ("pair-friction+supply", "pair", merge(friction(2.0), {"supply": {"supply_pressure_bar": 4.5}}), {},
     {"static_friction", "gain_change"}, set()),
    ("pair-overlap+spool", "pair", merge(overlap_worn(0.25), {"valve": {"spool_time_constant_s": SPOOL_S * 3}}), {},
     {"deadzone_shift", "valve_lag"}, TIMING),
    ("null-1", "null", {}, {}, set(), set()),
    ("null-2", "null", {}, {}, set(), set()),
    ("null-3", "null", {}, {}, set(), set()),
    ("null-4", "null", {}, {}, set(), set()),
]
FAST = {"friction-x2.5", "supply-4bar", "null-1"}
if os.environ.get("EPA_SANITIZER_RUN") == "1":
    FAST = {"supply-4bar", "null-1"}

# Recordings per case: (kind, arguments). Step runs use the commissioned law (pp-ffidz designed on
# the commissioned model); a null gets other targets and seeds than the others.
STEP_SECONDS, EXCITE_SECONDS = 6, 15


def recordings(index, null):
    shift = 15.0 * (index - 13) if null else 0.0  # new targets for each null (indices 14..17): 15-60 mm
    train = [("steps", [40 + shift / 4, 120 - shift / 3], 150 + shift), ("steps", [-60 - shift / 4, -150 + shift / 3], 350 - shift),
             ("excite", 1000 + index), ("excite", 2000 + index)]
    held = [("steps", [75 + shift / 5, -90 - shift / 5], 250 + shift / 2), ("excite", 3000 + index)]
    return train, held


def write_physics_config(path, tables):
    lines = ['schema = "epa-pneumatic/1"']
    for table, keys in tables.items():
        lines.append(f"[{table}]")
        lines += [f"{k} = {v!r}" for k, v in keys.items()]
    open(path, "w").write("\n".join(lines) + "\n")


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: {r.stderr.strip()}")
    return r


def commission(epa, folder):
    """The axis as commissioned: two 90 s excitations and epa identify, as the commissioning engineer runs them."""
    for seed in (1, 2):
        run([epa, "excite", "--plant", "physics", "--seed", str(seed), "--duration", "90", "--out", f"{folder}/ex{seed}.csv"])
    run([epa, "identify", f"{folder}/ex1.csv", "--validate", f"{folder}/ex2.csv", "--out", f"{folder}/model.toml"])
    return f"{folder}/model.toml"


def record_case(epa, folder, model, index, category, tables, options):
    config = os.path.join(folder, "plant.toml")
    write_physics_config(config, tables)
    extra_sim = ["--sensor-bits", str(options.get("sensor_bits", 0)), "--delay", str(options.get("delay_samples", 0))]
    extra_excite = ["--sensor-bits", str(options.get("sensor_bits", 0)), "--delay", str(options.get("delay_samples", 0))]
    train, held = recordings(index, category == "null")
    paths = {"train": [], "held": []}
    for role, plan in (("train", train), ("held", held)):
        for j, item in enumerate(plan):
            seed = 100 * index + 10 * (role == "held") + j + 1
            if item[0] == "steps":
                out = os.path.join(folder, f"{role}-{j}")
                run([epa, "simulate", "--plant", "physics", "--physics-config", config, "--model", model,
                     "--controller", "pp-ffidz", "--steps", ",".join(f"{s:.1f}" for s in item[1]), "--start", f"{item[2]:.1f}",
                     "--duration", str(STEP_SECONDS), "--noise", "0.1", "--seed", str(seed), "--out-dir", out, *extra_sim])
                paths[role] += sorted(os.path.join(out, f) for f in os.listdir(out) if f.endswith(".csv"))
            else:
                out = os.path.join(folder, f"{role}-{j}.csv")
                run([epa, "excite", "--plant", "physics", "--physics-config", config, "--seed", str(item[1]),
                     "--duration", str(EXCITE_SECONDS), "--out", out, *extra_excite])
                paths[role].append(out)
    return paths["train"], paths["held"]


def judge(category, expected, allowed, named, unexplained):
    if category == "null":
        return not named and not unexplained
    if category == "leak":
        return not named and unexplained
    return expected <= named and named <= expected | allowed and not unexplained


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("epa")
    ap.add_argument("--fast", action="store_true", help="the CI subset: " + ", ".join(sorted(FAST)))
    ap.add_argument("--keep", help="leave the commissioning, each case's runs and report here")
    ap.add_argument("--matrix", help="write the confusion matrix (Markdown) here")
    ap.add_argument("--check", action="store_true", help="exit 1 unless the issue's thresholds hold")
    ap.add_argument("--only", help="only the cases whose name matches this regular expression")
    ap.add_argument("--guard", action="store_true", help="exit 1 when a diagnosis failed or a null was blamed")
    args = ap.parse_args()

    cases = [(i, *c) for i, c in enumerate(CASES) if (not args.fast or c[0] in FAST) and (not args.only or re.search(args.only, c[0]))]
    results = []
    failures = 0
    with tempfile.TemporaryDirectory(prefix="epa-drift-") as tmp:
        root = args.keep or tmp
        os.makedirs(root, exist_ok=True)
        model = commission(args.epa, root)
        for index, name, category, tables, options, expected, allowed in cases:
            folder = os.path.join(root, name)
            os.makedirs(folder, exist_ok=True)
            train, held = record_case(args.epa, folder, model, index, category, tables, options)
            out = os.path.join(folder, "gap.json")
            t0 = time.monotonic()
            r = subprocess.run([args.epa, "diagnose", *train, "--holdout", *held, "--model", model, "--json", out,
                                "--report", os.path.join(folder, "gap.html")], capture_output=True, text=True, timeout=600)
            took = time.monotonic() - t0
            if r.returncode != 0:
                print(f"FAIL {name}: epa diagnose failed: {r.stderr.strip()[-400:]}")
                failures += 1
                results.append((name, category, expected, set(), True, 0.0, took, False))
                continue
            verdict = json.load(open(out))["verdict"]
            named = set(verdict.get("changes", []))
            unexplained = bool(verdict.get("changes_unexplained", True))
            reduction = float(verdict.get("changes_reduction_pct", 0.0))
            ok = judge(category, expected, allowed, named, unexplained)
            results.append((name, category, expected, named, unexplained, reduction, took, ok))
            print(f"{'ok  ' if ok else 'MISS'} {name:22s} named={sorted(named)} unexplained={unexplained} "
                  f"reduction={reduction:.0f}% {took:.2f}s", flush=True)

    correct = sum(r[7] for r in results)
    nulls = [r for r in results if r[1] == "null"]
    false_blame = sum(1 for r in nulls if r[3] or r[4])
    scored = [r for r in results if r[1] not in ("null", "leak", "sensor")]  # a replay cannot shrink rounding
    median_reduction = statistics.median(r[5] for r in scored) if scored else 0.0
    median_seconds = statistics.median(r[6] for r in results) if results else 0.0

    matrix = confusion_table(results, NAMES, "change")
    print(matrix)
    if args.matrix:
        open(args.matrix, "w").write(matrix + "\n")
    print(f"score: {correct}/{len(results)} cases correct, false_blame_on_null={false_blame}/{len(nulls)}, "
          f"median_reduction_pct={median_reduction:.1f}, median_seconds={median_seconds:.2f}")
    if args.guard and (failures or false_blame):
        print(f"drift guard: {failures} diagnosis failure(s), {false_blame} null(s) blamed")
        sys.exit(1)
    if args.check:
        ok = correct >= 0.9 * len(results) and false_blame == 0 and median_reduction >= 70.0 and median_seconds <= 10.0
        print("drift check: " + ("thresholds hold" if ok else "thresholds NOT met"))
        sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
