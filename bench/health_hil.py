#!/usr/bin/env python3
"""The model-health monitor end to end, hardware in the loop: `epa serve` over modbus-io against
`epa plant-server --plant physics --sync-to-valve-writes --control-stdin`, its running set's model
MODEL (identified from the same plant: bench/health_hil.sh). pp-traj moves between seeded random
targets, each written when the last one has ended; after CHANGE_AT moves one physical change is
made by `physics` lines on the plant-server's stdin, as wear would make it while the axis runs.
After every move the monitor's verdict is read over Modbus (health_state, health_effect,
health_ratio), as an HMI reads it.

  bench/health_hil.py EPA MODEL [MOVES=70] [CHANGE_AT=32] [--law LAW] [CASE ...]

Cases: friction-x2, supply-4.5bar, overlap-0.25V, spool-x3, null (no change; all when none are
given). LAW moves the axis (pp-traj when not given). Prints one line per case and "health hil: N
of M changes named, median K moves after the change, latest L; false alarms F in U unchanged
moves".
"""
import json
import os
import statistics
import sys
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "support"))
from epa_appliance import Appliance, read_point, read_register_map, wait_until, write_point  # noqa: E402
from plant_server import PlantServer  # noqa: E402

REGISTERS = os.path.join(ROOT, "registers", "epa.csv")
RUN = 1
DRIFTING, UNEXPLAINED = 3, 4                      # health_state
EFFECTS = {1: "static_friction", 2: "gain_change", 3: "deadzone_shift", 4: "valve_lag", 5: "input_delay"}  # health_effect
# Each case's change of the physics plant's defaults (src/plant/pneumatic_params.hpp: friction 40 /
# 25 N, supply 6 bar, overlap 1.2 V, spool 5 ms), as bench/health_drift.cpp makes them:
# (name, physics lines, the effect the diagnosis names for it, the direction of its ratio).
CASES = {
    "friction-x2": (["static_friction_n 80", "coulomb_friction_n 50"], "static_friction", +1),
    "supply-4.5bar": (["supply_pressure_bar 4.5"], "gain_change", -1),
    "overlap-0.25V": (["overlap_pos_v 0.95"], "deadzone_shift", -1),
    "spool-x3": (["spool_time_constant_s 0.015"], "valve_lag", +1),
    "null": ([], "", 0),
}
MOVE_END_BOUND_S = 8.0


def run_case(epa, model, points, name, moves, change_at, law, seed):
    lines, expected, direction = CASES[name]
    plant = PlantServer(epa, "physics", initial_position_mm=250.0, extra_args=["--sync-to-valve-writes"])
    app = None
    try:
        extra = (f'[controller]\nkind = "{law}"\n'
                 f'model = "{model}"\n'
                 '[hal]\nbackend = "modbus-io"\n'
                 f'[hal.modbus_io]\nport = {plant.port}\n'
                 '[health]\nenabled = true\n')
        app = Appliance(epa, REGISTERS, extra_config=extra, web_static_dir=os.path.join(ROOT, "web"))
        write_point(app.client, points, "mode", RUN)
        wait_until(lambda: read_point(app.client, points, "mode") == RUN, 3.0)
        rng_state = seed * 7919 + 13
        target, named_after, ratio, alarms, seen = 250.0, None, None, 0, 0
        previous = read_point(app.client, points, "health_state")
        for m in range(moves):
            if m == change_at:
                for line in lines:
                    answer = plant.command("physics " + line)
                    if not answer.startswith("ok"):
                        raise RuntimeError(f"plant-server refused 'physics {line}': {answer}")
            rng_state = (rng_state * 6364136223846793005 + 1442695040888963407) % 2**64
            u = (rng_state >> 11) / 2**53
            size = 10.0 + 30.0 * u if u < 0.4 else 40.0 + 160.0 * u
            direction_mm = -1.0 if target > 400 else 1.0 if target < 100 else (-1.0 if (rng_state >> 7) & 1 else 1.0)
            target = min(480.0, max(20.0, target + direction_mm * size))
            number = read_point(app.client, points, "move_number")
            write_point(app.client, points, "setpoint_mm", target)
            wait_until(lambda: read_point(app.client, points, "move_number") > number, MOVE_END_BOUND_S)
            time.sleep(0.3)  # stays: the piston rests between moves, so the next starts from rest
            state = read_point(app.client, points, "health_state")
            seen = read_point(app.client, points, "health_moves_seen")
            if state in (DRIFTING, UNEXPLAINED) and state != previous and (m < change_at or not lines):
                alarms += 1
            previous = state
            if m >= change_at and lines and named_after is None and state == DRIFTING \
                    and EFFECTS.get(read_point(app.client, points, "health_effect")) == expected:
                named_after = m + 1 - change_at
                ratio = read_point(app.client, points, "health_ratio")
        right_way = named_after is not None and (ratio - 1.0) * direction > 0
        final = (read_point(app.client, points, "health_state"), EFFECTS.get(read_point(app.client, points, "health_effect"), ""),
                 read_point(app.client, points, "health_ratio"))
        with urllib.request.urlopen(f"http://127.0.0.1:{app.web_port}/api/faults", timeout=5) as r:
            history = json.load(r)
        noted = [f for f in history.get("faults", []) if f.get("name") == "model-health"]  # newest first
        final = final + (len(noted),)
        if os.environ.get("EPA_HEALTH_TRACE"):
            with urllib.request.urlopen(f"http://127.0.0.1:{app.web_port}/api/health", timeout=5) as r:
                health = json.load(r)
            print(f"  gaps: window {health['window_gap_mm']} mm, baseline {health['baseline_gap_mm']} mm; {health['reason']}")
            for f in reversed(noted):
                print(f"  fault history: {f['text']}")
            for j in health["trend"][-6:]:
                print(f"  move {j['move']}: " + ", ".join(f"{e['effect']} x{e['ratio']:.2f} ({100 * e['reduction']:.0f} %)"
                                                       for e in j["estimates"]))
        return named_after if right_way else None, ratio, alarms, seen, (change_at if lines else moves), final
    finally:
        if app:
            app.stop()
            app.remove()
        plant.stop()


def main(argv):
    if len(argv) < 3:
        print("usage:" + next(line for line in __doc__.splitlines() if "health_hil.py EPA" in line), file=sys.stderr)
        return 2
    law = "pp-traj"
    if "--law" in argv:
        i = argv.index("--law")
        law = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    epa, model = argv[1], os.path.abspath(argv[2])
    moves = int(argv[3]) if len(argv) > 3 else 70
    change_at = int(argv[4]) if len(argv) > 4 else 32
    names = argv[5:] or list(CASES)
    points = read_register_map(REGISTERS)
    named, changes, alarms_total, unchanged = [], 0, 0, 0
    for name in names:
        start = time.monotonic()
        after, ratio, alarms, seen, unchanged_moves, final = run_case(epa, model, points, name, moves, change_at, law, seed=1)
        alarms_total += alarms
        unchanged += unchanged_moves
        if CASES[name][0]:
            changes += 1
            if after is not None:
                named.append(after)
        verdict = ("not named" if after is None else f"named {CASES[name][1]} {after} moves after the change (ratio {ratio:.2f})") \
            if CASES[name][0] else "no change"
        state, effect, final_ratio, noted = final
        print(f"case {name} ({law}): {verdict}; {alarms} false alarm(s) before the change; {seen} moves judged; at the end: "
              f"health_state {state} {effect} ratio {final_ratio:.2f}; {noted} model-health entries in the fault history; "
              f"{time.monotonic() - start:.0f} s")
    median = f"{statistics.median(named):.0f}" if named else "-"
    latest = f"{max(named)}" if named else "-"
    print(f"health hil: {len(named)} of {changes} changes named, median {median} moves after the change, latest {latest}; "
          f"false alarms {alarms_total} in {unchanged} unchanged moves")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
