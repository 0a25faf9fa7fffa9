#!/usr/bin/env python3
"""Mode EXCITE over Modbus, as a commissioning engineer drives it with a client this project did not
write (pymodbus): `epa serve` on the simulated plant with the piston at rest mid-stroke.

    excite_test.py <epa binary> <source dir>

Checks: the excite_* holding registers read the configuration's [excite] settings; written while
locked they get exception 04, after the unlock they are taken as one FC16 block, and a minimum
above the maximum gets 03; mode 4 from RUN gets 04; from STOP the experiment runs (mode reads 4,
excite_left_s counts down, the valve stays within the amplitude written), then the appliance is
back in STOP by itself with the valve safe; the run file is open-loop with the seed written, and
the store's run history holds it.
"""
import glob
import math
import os
import sqlite3
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import UNIT, Appliance, Checks, f32_value, f32_words, u32_value, u32_words, unlock, wait_until  # noqa: E402

ILLEGAL_VALUE = 0x03
CANNOT_APPLY = 0x04
MODE = 2             # holding: 0 stop, 1 run, 2 manual, 4 excite
SETPOINT = 0         # holding 0-1, float32 ABCD
EXCITE = 30          # holding 30-37: amplitude_min_v, amplitude_max_v, duration_s (float32), seed (uint32)
VALVE = 4            # input 4-5, float32
EXCITE_LEFT = 134    # input 134-135, float32
DURATION_S = 3.0
AMPLITUDE_MAX_V = 2.0
SEED = 7


def main():
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    epa, src = sys.argv[1], sys.argv[2]
    check = Checks()
    failures = check.failures

    def refused(rr, code, what):
        check(rr.isError() and getattr(rr, "exception_code", None) == code, f"{what} -> exception {code:02X} ({rr})")

    def holding(address, count):
        rr = app.client.read_holding_registers(address, count, slave=UNIT)
        if rr.isError():
            raise RuntimeError(f"read holding {address}+{count}: {rr}")
        return rr.registers

    def input_f32(address):
        rr = app.client.read_input_registers(address, 2, slave=UNIT)
        if rr.isError():
            raise RuntimeError(f"read input {address}: {rr}")
        return f32_value(rr.registers, "ABCD")

    def wait_mode(expected, timeout_s):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if holding(MODE, 1)[0] == expected:
                return True
            time.sleep(0.02)
        return False

    reg_map = os.path.join(src, "registers", "epa.csv")
    app = Appliance(epa, reg_map, "[hal.sim]\ninitial_position_mm = 250.0\nnoise_mm = 0.1\n"
                                  "[excite]\nduration_s = 4.0\nseed = 3\n")
    try:
        c = app.client
        h = holding(EXCITE, 8)
        settings = (f32_value(h[0:2], "ABCD"), f32_value(h[2:4], "ABCD"), f32_value(h[4:6], "ABCD"), u32_value(h[6:8]))
        check(all(math.isclose(a, b, rel_tol=1e-6) for a, b in zip(settings, (0.2, 3.0, 4.0, 3))),
              f"excite_* read the configuration's [excite] settings {settings}")

        block = f32_words(0.2, "ABCD") + f32_words(AMPLITUDE_MAX_V, "ABCD") + f32_words(DURATION_S, "ABCD") + u32_words(SEED)
        refused(c.write_registers(EXCITE, block, slave=UNIT), CANNOT_APPLY, "excite_* block while locked")
        check(not unlock(c).isError(), "unlock")
        refused(c.write_registers(EXCITE, f32_words(2.5, "ABCD") + f32_words(2.0, "ABCD"), slave=UNIT), ILLEGAL_VALUE,
                "excite_amplitude_min_v 2.5 above excite_amplitude_max_v 2.0")
        rr = c.write_registers(EXCITE, block, slave=UNIT)
        check(not rr.isError(), f"excite_* block after the unlock ({rr})")
        deadline = time.monotonic() + 2.0  # the registers show the loop's settings: from its next cycle on
        while True:
            h = holding(EXCITE, 8)
            taken = math.isclose(f32_value(h[2:4], "ABCD"), AMPLITUDE_MAX_V) and u32_value(h[6:8]) == SEED
            if taken or time.monotonic() > deadline:
                break
            time.sleep(0.02)
        check(taken, f"excite_* read back the block ({h})")

        # RUN holds the piston where it is; EXCITE is refused there.
        check(not c.write_registers(SETPOINT, f32_words(250.0, "ABCD"), slave=UNIT).isError(), "setpoint 250")
        check(not c.write_register(MODE, 1, slave=UNIT).isError(), "mode 1 (run)")
        check(wait_mode(1, 2.0), "mode reads 1")
        refused(c.write_register(MODE, 4, slave=UNIT), CANNOT_APPLY, "mode 4 (excite) from RUN")
        check(not c.write_register(MODE, 0, slave=UNIT).isError(), "mode 0 (stop)")
        check(wait_mode(0, 2.0), "mode reads 0")

        rr = c.write_register(MODE, 4, slave=UNIT)
        check(not rr.isError(), f"mode 4 (excite) from STOP ({rr})")
        check(wait_mode(4, 2.0), "mode reads 4")
        started = time.monotonic()
        lefts, valves = [], []
        while holding(MODE, 1)[0] == 4 and time.monotonic() - started < DURATION_S + 10.0:
            lefts.append(input_f32(EXCITE_LEFT))
            valves.append(input_f32(VALVE))
            time.sleep(0.02)
        took = time.monotonic() - started
        check(holding(MODE, 1)[0] == 0, f"back in STOP by itself after {took:.2f} s")
        check(DURATION_S - 0.5 < took < DURATION_S + 3.0, f"the experiment took about {DURATION_S} s ({took:.2f} s)")
        check(len(lefts) > 10 and 0.0 < lefts[0] <= DURATION_S and lefts[-1] < lefts[0],
              f"excite_left_s counted down ({lefts[0] if lefts else None} -> {lefts[-1] if lefts else None})")
        check(valves and max(abs(v) for v in valves) <= AMPLITUDE_MAX_V + 1e-6 and max(abs(v) for v in valves) > 0.5,
              f"the valve moved within +-{AMPLITUDE_MAX_V} V (largest seen {max((abs(v) for v in valves), default=0):.3f})")
        check(input_f32(VALVE) == 0.0 and input_f32(EXCITE_LEFT) == 0.0, "after it: the valve safe, excite_left_s 0")
        # The recorder thread polls every 20 ms and writes the file whole (a rename): wait for it, bounded.
        wait_until(lambda: glob.glob(os.path.join(app.dir, "runs", f"excite-*-seed{SEED}.csv")), 5.0, 0.02)
    finally:
        status = app.stop()
    check(status == 0, f"epa serve stopped cleanly ({status})")

    files = glob.glob(os.path.join(app.dir, "runs", f"excite-*-seed{SEED}.csv"))
    check(len(files) == 1, f"one run file of the experiment ({files})")
    if files:
        text = open(files[0]).read()
        rows = [line for line in text.splitlines() if line and not line.startswith("#")]
        check("# controller=open-loop" in text and f"# excitation_seed={SEED}" in text and "# excitation_end=complete" in text,
              "its header: controller=open-loop, the seed, excitation_end=complete")
        check(rows and rows[0].split(",") == ["t_s", "y_mm", "u_V"], f"its columns: t_s, y_mm, u_V ({rows[:1]})")
        check(len(rows) - 1 == round(DURATION_S / 0.005), f"{round(DURATION_S / 0.005)} samples ({len(rows) - 1})")
        db = sqlite3.connect(app.db)
        runs = db.execute("SELECT path, controller, samples FROM runs").fetchall()
        db.close()
        check((files[0], "open-loop", round(DURATION_S / 0.005)) in runs, f"the store's run history holds it ({runs})")
    if not failures:
        app.remove()
    else:
        print(f"kept {app.dir} for a look; the appliance's log:\n{app.log_text()}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
