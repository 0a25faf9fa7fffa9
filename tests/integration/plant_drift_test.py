#!/usr/bin/env python3
"""A plant that drifts while it runs: `epa plant-server --control-stdin` takes `physics KEY VALUE`
lines and the running physics plant changes from its next step on. Judged from outside, by Debian's
pymodbus as the master: the piston moves under a 5 V valve command; after `physics` lines that
raise its friction above what the supply can push, the same command moves it no more. Bad lines
are refused naming what was wrong, and the Hammerstein plant refuses `physics` lines.

    plant_drift_test.py <epa binary> <source dir>

Loopback only, bounded waits; the plant-servers are stopped by their PIDs. Exit 0 when every check holds.
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import UNIT, Checks, ModbusTcpClient  # noqa: E402
from plant_server import PlantServer  # noqa: E402

MM_PER_VOLT = 50.0  # the physics plant's sensor: 0-10 V over its 500 mm stroke
COUNTS_PER_VOLT = 32767 / 10.0


def position_mm(client):
    r = client.read_input_registers(0, 1, slave=UNIT)
    return r.registers[0] / COUNTS_PER_VOLT * MM_PER_VOLT


def drive(client, valve_v, seconds):
    """Writes the valve command every 5 ms for `seconds`, as a master does; the position moved, mm."""
    start = position_mm(client)
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        client.write_register(0, int(round(valve_v * COUNTS_PER_VOLT)) & 0xFFFF, slave=UNIT)
        time.sleep(0.005)
    client.write_register(0, 0, slave=UNIT)
    time.sleep(0.1)
    return position_mm(client) - start


def main():
    epa = os.path.abspath(sys.argv[1])
    checks = Checks()
    plant = PlantServer(epa, "physics")
    client = ModbusTcpClient("127.0.0.1", port=plant.port, timeout=1.0)
    try:
        checks(client.connect(), f"pymodbus connected to the plant-server on port {plant.port}")
        moved = drive(client, 5.0, 0.15)
        checks(moved > 20.0, f"5 V for 0.15 s moves the piston: {moved:+.1f} mm")
        answer = plant.command("physics supply_pressure_bar 40")
        checks(answer.startswith("error:") and "supply_pressure_bar = 40" in answer and "range" in answer,
                     f"a value out of range is refused naming the key and its range: {answer!r}")
        answer = plant.command("physics supply_presure_bar 4.5")
        checks(answer.startswith("error:") and "unknown key 'supply_presure_bar'" in answer,
                     f"an unknown key is refused by name: {answer[:90]!r}")
        answer = plant.command("physics supply_pressure_bar")
        checks(answer.startswith("error:") and "KEY VALUE" in answer, f"a line without a value is refused: {answer!r}")
        answer = plant.command("physics static_friction_n 2000")
        checks(answer.startswith("error:") and "too coarse for the Stribeck slope" in answer,
               f"a change the plant's sub-steps cannot integrate is refused, saying why: {answer[:100]!r}")
        # 6 bar on a 32 mm bore pushes at most about 480 N: friction of 2,000 N holds the piston.
        for line in ("physics stribeck_velocity_mps 0.2", "physics static_friction_n 2000", "physics friction.coulomb_friction_n 2000"):
            answer = plant.command(line)
            checks(answer == "ok " + line, f"'{line}' is taken: {answer!r}")
        moved = drive(client, -5.0, 0.15)
        checks(abs(moved) < 1.0, f"after it, -5 V for 0.15 s moves the piston no more: {moved:+.2f} mm")
        answer = plant.command("physics static_friction_n 40")
        checks(answer.startswith("error:") and "coulomb_friction_n" in answer,
                     f"a change that breaks a rule between keys (sliding above breakaway friction) is refused: {answer!r}")
        for line in ("physics coulomb_friction_n 25", "physics static_friction_n 40", "physics stribeck_velocity_mps 0.02"):
            plant.command(line)
        moved = drive(client, -5.0, 0.15)
        checks(moved < -20.0, f"friction set back, -5 V moves it again: {moved:+.1f} mm")
    finally:
        client.close()
        plant.stop()

    hammerstein = PlantServer(epa, "hammerstein")
    try:
        answer = hammerstein.command("physics supply_pressure_bar 4.5")
        checks(answer.startswith("error:") and "Hammerstein" in answer and "--plant physics" in answer,
                     f"the Hammerstein plant refuses a physics line, naming why: {answer!r}")
    finally:
        hammerstein.stop()
    return 1 if checks.failures else 0


if __name__ == "__main__":
    sys.exit(main())
