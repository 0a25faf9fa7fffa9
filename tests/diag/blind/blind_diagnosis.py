#!/usr/bin/env python3
"""Blind test of `epa diagnose`: rigs from truth_rigs.py (forms the diagnosis does not fit), 6
training and 3 held-out runs per case (closed-loop FF-IDZ and NG-IDZ step sequences, open-loop
ramps and pulse trains), the diagnosis run on each as a user would, and a score.

    blind_diagnosis.py EPA_BINARY [--fast] [--seeds N] [--first-seed K] [--keep DIR] [--matrix FILE] [--check] [--only REGEX]

A case is correct when: its effects are all named, nothing outside them and their allowed
companions is named, and `unexplained` is false (a named effect with `unexplained: true` cannot
be acted on); effect-free rigs when nothing is named and `unexplained` is false; disturbances
outside the vocabulary when `unexplained` is true. Prints one line per case, the confusion matrix,
and the score line of the withheld benchmark:

    score: C/N cases correct, false_blame_on_null=F/M, median_reduction_pct=R, median_seconds=S

--check exits 1 unless the issue's thresholds hold (>= 20/22 of the cases, scaled; no false blame;
median reduction >= 70 %; median <= 10 s; >= 3/4 of the pairs with both named).
"""
import argparse
import re
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import truth_rigs as tr  # noqa: E402
from confusion_table import confusion_table  # noqa: E402

DELAY_COMPANIONS = {"input_delay", "valve_lag"}

# name, category, truth effects (a function of nothing: fresh state per rig), expected names,
# allowed companions. Two or more magnitudes and several forms per phenomenon.
CASES = [
    ("karnopp-light", "friction", lambda: {"karnopp": (0.3, 0.18, 20.0, 0.002)}, {"static_friction"}, {"deadzone_shift"}),
    ("karnopp-strong", "friction", lambda: {"karnopp": (0.6, 0.35, 20.0, 0.002)}, {"static_friction"}, {"deadzone_shift"}),
    ("lugre-light", "friction", lambda: {"lugre": (0.35, 0.2, 15.0, 2.0)}, {"static_friction"}, {"deadzone_shift"}),
    ("lugre-strong", "friction", lambda: {"lugre": (0.7, 0.4, 15.0, 2.0)}, {"static_friction"}, {"deadzone_shift"}),
    ("compress-mild", "position", lambda: {"compress_mm": 500.0}, {"position_dependent_gain"}, set()),
    ("compress-strong", "position", lambda: {"compress_mm": 250.0}, {"position_dependent_gain"}, set()),
    ("cos-dip-mild", "position", lambda: {"cos_dip": 0.25}, {"position_dependent_gain"}, set()),
    ("cos-dip-strong", "position", lambda: {"cos_dip": 0.45}, {"position_dependent_gain"}, set()),
    ("spool-2nd-8hz", "spool", lambda: {"spool": tr.SecondOrderSpool(8.0, 0.7)}, {"valve_lag"}, DELAY_COMPANIONS),
    ("spool-2nd-4hz", "spool", lambda: {"spool": tr.SecondOrderSpool(4.0, 0.8)}, {"valve_lag"}, DELAY_COMPANIONS),
    ("spool-slew-40", "spool", lambda: {"spool": tr.SlewLimitedSpool(40.0)}, {"valve_lag"}, DELAY_COMPANIONS),
    ("spool-slew-15", "spool", lambda: {"spool": tr.SlewLimitedSpool(15.0)}, {"valve_lag"}, DELAY_COMPANIONS),
    ("delay-2.5", "delay", lambda: {"spool": tr.FractionalDelay(2.5)}, {"input_delay"}, DELAY_COMPANIONS),
    ("delay-5.5", "delay", lambda: {"spool": tr.FractionalDelay(5.5)}, {"input_delay"}, DELAY_COMPANIONS),
    ("line-3+lag", "delay", lambda: {"spool": tr.FractionalDelay(3.3, 0.004)}, {"input_delay"}, DELAY_COMPANIONS),
    ("tanh-knee-soft", "flow", lambda: {"tanh_knee": (1.6, 1.2)}, {"flow_saturation"}, {"gain_change"}),
    ("tanh-knee-hard", "flow", lambda: {"tanh_knee": (0.9, 0.6)}, {"flow_saturation"}, {"gain_change"}),
    ("choke-asym", "flow", lambda: {"hard_limit": (1.2, 0.8)}, {"flow_saturation"}, {"gain_change"}),
    ("supply-4.8bar", "supply", lambda: {"supply_bar": 4.8, "retract_factor": 0.95}, {"gain_change"}, set()),
    ("supply-4.0bar", "supply", lambda: {"supply_bar": 4.0, "retract_factor": 0.92}, {"gain_change"}, set()),
    ("supply-sag", "supply", lambda: {"supply_bar": 5.6, "sag_bar_per_s": 0.06}, {"gain_change"}, set()),
    ("breakpoints-out", "breakpoints", lambda: {"shift_r": 0.25, "shift_l": -0.2}, {"deadzone_shift"}, set()),
    ("breakpoints-soft", "breakpoints", lambda: {"shift_r": -0.2, "shift_l": 0.15, "soft_edge_v": 0.3}, {"deadzone_shift"}, set()),
    ("adc-10bit", "sensor", lambda: {"adc_bits": 10}, {"sensor_quantization"}, set()),
    ("adc-8bit", "sensor", lambda: {"adc_bits": 8}, {"sensor_quantization"}, set()),
    ("encoder-1mm", "sensor", lambda: {"encoder_mm": 1.0}, {"sensor_quantization"}, set()),
    ("pair-friction+position", "pair", lambda: {"karnopp": (0.5, 0.3, 20.0, 0.002), "cos_dip": 0.4},
     {"static_friction", "position_dependent_gain"}, {"deadzone_shift"}),
    ("pair-spool+flow", "pair", lambda: {"spool": tr.SecondOrderSpool(5.0, 0.7), "tanh_knee": (1.0, 0.7)},
     {"valve_lag", "flow_saturation"}, DELAY_COMPANIONS | {"gain_change"}),
    ("pair-delay+sensor", "pair", lambda: {"spool": tr.FractionalDelay(4.5), "adc_bits": 8},
     {"input_delay", "sensor_quantization"}, DELAY_COMPANIONS),
    ("pair-supply+friction", "pair", lambda: {"supply_bar": 4.2, "lugre": (0.6, 0.35, 15.0, 2.0)},
     {"gain_change", "static_friction"}, {"deadzone_shift"}),
    ("pair-position+spool", "pair", lambda: {"compress_mm": 250.0, "spool": tr.SlewLimitedSpool(20.0)},
     {"position_dependent_gain", "valve_lag"}, DELAY_COMPANIONS),
    ("null-a", "null", lambda: {}, set(), set()),
    ("null-b", "null", lambda: {}, set(), set()),
    ("null-c", "null", lambda: {}, set(), set()),
    ("null-d", "null", lambda: {}, set(), set()),
    ("load-periodic", "outside", lambda: {"load_v": 0.5, "load_hz": 0.7}, None, None),
    ("sensor-drift", "outside", lambda: {"drift_mm_s": 1.5}, None, None),
    ("sensor-spikes", "outside", lambda: {"spike_prob": 0.01}, None, None),
]
FAST = ["karnopp-strong", "cos-dip-strong", "spool-2nd-4hz", "delay-5.5", "tanh-knee-hard", "supply-4.0bar",
        "breakpoints-out", "adc-8bit", "pair-friction+position", "null-a", "load-periodic"]
# Training runs, then held-out runs, as a commissioning engineer records them.
TRAIN = ["pp-ffidz", "pp-ngidz", "pp-ffidz", "ramps", "pulses", "pp-ngidz"]
HELDOUT = ["pp-ffidz", "pp-ngidz", "pulses"]
NAMES = ["gain_change", "deadzone_shift", "input_delay", "valve_lag", "static_friction", "flow_saturation",
         "position_dependent_gain", "sensor_quantization"]


def write_case(folder, effects_factory, seed):
    rng = random.Random(seed)
    nominal = tr.perturbed_nominal(rng)
    paths = []
    for i, kind in enumerate(TRAIN + HELDOUT):
        rig = tr.Rig(nominal, effects_factory(), rng, x0_mm=rng.uniform(180.0, 320.0))
        seconds = rng.uniform(12.0, 15.0)
        controller, rows = (tr.closed_loop_run(rig, kind, seconds, rng) if kind.startswith("pp")
                            else tr.open_loop_run(rig, kind, seconds, rng))
        path = os.path.join(folder, f"run-{i + 1}-{kind}.csv")
        tr.write_run(path, controller, rows)
        paths.append(path)
    return paths[:len(TRAIN)], paths[len(TRAIN):]


def judge(category, expected, allowed, named, unexplained):
    if category == "outside":
        return unexplained
    if category == "null":
        return not named and not unexplained
    return expected <= named and named <= expected | allowed and not unexplained


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("epa")
    ap.add_argument("--fast", action="store_true", help="the CI subset (one case per phenomenon, one seed)")
    ap.add_argument("--seeds", type=int, default=1, help="the last seed: seeds --first-seed..SEEDS run (the whole set: 38 cases each)")
    ap.add_argument("--first-seed", type=int, default=1,
                    help="start at this seed (seeds 3 and 4, never used to change the diagnosis: --first-seed 3 --seeds 4)")
    ap.add_argument("--keep", help="leave each case's runs and report here")
    ap.add_argument("--matrix", help="write the confusion matrix (Markdown) here")
    ap.add_argument("--check", action="store_true", help="exit 1 unless the issue's thresholds hold")
    ap.add_argument("--only", help="only the cases whose name matches this regular expression (while working on one)")
    args = ap.parse_args()

    cases = [c for c in CASES if (not args.fast or c[0] in FAST) and (not args.only or re.search(args.only, c[0]))]
    results = []
    with tempfile.TemporaryDirectory(prefix="epa-blind-") as tmp:
        for seed in range(args.first_seed, args.seeds + 1):
            for name, category, factory, expected, allowed in cases:
                folder = os.path.join(args.keep or tmp, f"{name}-s{seed}")
                os.makedirs(folder, exist_ok=True)
                # The seed mixes the case name in, so no two cases share their noise.
                train, held = write_case(folder, factory, seed * 1000003 + sum(map(ord, name)))
                out = os.path.join(folder, "gap.json")
                t0 = time.monotonic()
                r = subprocess.run([args.epa, "diagnose", *train, "--holdout", *held, "--json", out,
                                    "--report", os.path.join(folder, "gap.html")],
                                   capture_output=True, text=True, timeout=600)
                took = time.monotonic() - t0
                if r.returncode != 0:
                    print(f"{name} s{seed}: epa diagnose failed: {r.stderr.strip()}")
                    results.append((name, category, expected, set(), True, 0.0, took, False))
                    continue
                verdict = json.load(open(out))["verdict"]
                named, unexplained = set(verdict["effects"]), bool(verdict["unexplained"])
                ok = judge(category, expected, allowed, named, unexplained)
                results.append((name, category, expected, named, unexplained, verdict["reduction_pct"], took, ok))
                print(f"{'ok  ' if ok else 'MISS'} {name:24s} s{seed} named={sorted(named)} unexplained={unexplained} "
                      f"reduction={verdict['reduction_pct']:.0f}% {took:.2f}s", flush=True)

    correct = sum(r[7] for r in results)
    nulls = [r for r in results if r[1] == "null"]
    false_blame = sum(1 for r in nulls if r[3])
    scored = [r for r in results if r[1] not in ("null", "outside")]
    median_reduction = statistics.median(r[5] for r in scored) if scored else 0.0
    median_seconds = statistics.median(r[6] for r in results)
    pairs = [r for r in results if r[1] == "pair"]
    pairs_both = sum(1 for r in pairs if r[2] <= r[3])

    matrix = confusion_table(results, NAMES, "truth")
    print(matrix)
    if args.matrix:
        open(args.matrix, "w").write(matrix + "\n")
    print(f"pairs with both named: {pairs_both}/{len(pairs)}")
    print(f"score: {correct}/{len(results)} cases correct, false_blame_on_null={false_blame}/{len(nulls)}, "
          f"median_reduction_pct={median_reduction:.1f}, median_seconds={median_seconds:.2f}")
    if args.check:
        ok = (correct >= len(results) * 20 / 22 and false_blame == 0 and median_reduction >= 70.0 and
              median_seconds <= 10.0 and (not pairs or pairs_both >= 0.75 * len(pairs)))
        print("blind check: " + ("thresholds hold" if ok else "thresholds NOT met"))
        sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
