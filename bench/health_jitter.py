#!/usr/bin/env python3
"""The scan cycle's period jitter with the model-health monitor judging every move, against the
same appliance with the monitor off ([health] enabled = false), in the same run of this script.

Each run serves the physics sim plant with MODEL (a model file with a [stick_slip] table, so the
monitor has a model: bench/health_jitter.sh identifies one) and moves pp-traj between seeded
random targets over Modbus, one every MOVE_S seconds, for SECONDS. The monitor's baseline is one
window (8 moves), so that it judges every move after the eighth. It then reads loop_jitter_p99_us
and the monitor's health_moves_seen. Runs alternate off / on, RUNS of each; the figure is the
ratio of the medians.

  bench/health_jitter.py EPA MODEL [RUNS=3] [SECONDS=60] [MOVE_S=2.5]

Prints one line per run and "health jitter p99: on N us / off N us = R x (bound 1.2 x)".
Python 3 with pymodbus (Debian's python3-pymodbus).
"""
import os
import random
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "support"))
from epa_appliance import Appliance, read_point, read_register_map, wait_until, write_point  # noqa: E402

REGISTERS = os.path.join(ROOT, "registers", "epa.csv")
RUN = 1  # mode
# The baseline shortened to one window: the monitor judges (fits every effect to a window, what a
# move costs it from then on) for most of the run, not only appends moves while it learns.
BASELINE_MOVES = 8


def one_run(epa, model, points, monitor_on, seconds, move_s, seed):
    extra = ('[controller]\nkind = "pp-traj"\n'
             f'model = "{model}"\n'
             '[hal.sim]\nplant = "physics"\n'
             f'[health]\nenabled = {"true" if monitor_on else "false"}\n'
             f'baseline_moves = {BASELINE_MOVES}\n')
    app = Appliance(epa, REGISTERS, extra_config=extra)
    try:
        write_point(app.client, points, "mode", RUN)
        wait_until(lambda: read_point(app.client, points, "mode") == RUN, 3.0)
        rng = random.Random(seed)
        target = 250.0
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            target = min(470.0, max(30.0, target + rng.choice((-1, 1)) * rng.uniform(30.0, 200.0)))
            write_point(app.client, points, "setpoint_mm", target)
            time.sleep(move_s)  # stays: the move's time, the stimulus
        return tuple(read_point(app.client, points, name) for name in ("loop_jitter_p99_us", "health_moves_seen", "health_state"))
    finally:
        app.stop()
        app.remove()


def main(argv):
    if len(argv) < 3:
        print("usage:" + next(line for line in __doc__.splitlines() if "health_jitter.py EPA" in line), file=sys.stderr)
        return 2
    epa, model = argv[1], os.path.abspath(argv[2])
    runs = int(argv[3]) if len(argv) > 3 else 3
    seconds = float(argv[4]) if len(argv) > 4 else 60.0
    move_s = float(argv[5]) if len(argv) > 5 else 2.5
    points = read_register_map(REGISTERS)
    jitter = {False: [], True: []}
    for run in range(runs):
        for on in (False, True):
            p99, seen, state = one_run(epa, model, points, on, seconds, move_s, seed=run + 1)
            jitter[on].append(p99)
            print(f"run {run + 1} monitor {'on ' if on else 'off'}: jitter p99 {p99:.0f} us, moves judged {seen}, health_state {state}")
            if on and seen <= BASELINE_MOVES and seconds >= 30:
                print("health_jitter: the monitor made no judgement: the figure would not measure it", file=sys.stderr)
                return 1
    on, off = statistics.median(jitter[True]), statistics.median(jitter[False])
    print(f"health jitter p99: on {on:.0f} us / off {off:.0f} us = {on / off if off > 0 else float('nan'):.2f} x (bound 1.2 x)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
