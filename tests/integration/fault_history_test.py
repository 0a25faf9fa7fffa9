#!/usr/bin/env python3
"""The fault history end to end: faults that a client resets as fast as it can still
appear, with their cause, in GET /api/faults, in the Modbus registers (read with pymodbus, a
client this project did not write), in `epa faults` and in the log, in the order they happened.

    fault_history_test.py <epa binary> <source dir>

`epa serve` on the simulated plant, with [limits] narrowed so that three faults can be caused
from a client: following-error in RUN (plain PP, which stalls in the dead band, asked for 10 mm: the
piston stands while the motion it should follow goes on; 10 ms allowed for a 5 mm error),
heartbeat-lost in MANUAL (the heartbeat stops for 0.3 s) and soft-limit in MANUAL (3 V drives the
piston past soft_max_mm = 300), the piston at rest before each. A second client polls fault_active in a tight loop and writes
reset the moment it reads 1, so each fault is latched for a cycle or two, far less than the
supervisor's 50 ms tick (such a fault must not be logged as "FAULT none: no fault").
Checked: the three entries newest first with the right code, name, mode, position and setpoint;
fault_history_count and the newest entries over Modbus (empty slots: code 0, NaN); `epa faults`
(table and --json) from the database while the appliance runs; the log's FAULT lines carry the
cause and none says "none"; after a restart the history is still there.
"""
import json
import math
import os
import re
import subprocess
import sys
import threading
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, UNIT, Appliance, Checks, ModbusTcpClient, f32_value, f32_words, u32_value, u32_words, wait_until, wait_until_steady  # noqa: E402

SOFT_MAX_MM = 300.0
MANUAL_V = 1.5
CONFIG = ("[limits]\n"
          f"soft_max_mm = {SOFT_MAX_MM}\n"
          "setpoint_max_mm = 290.0\n"
          "following_error_mm = 5.0\n"
          "following_error_time_s = 0.01\n"
          "heartbeat_timeout_s = 0.3\n"
          "[hal.sim]\n"
          "initial_position_mm = 100.0\n")
MODES = {0: "stop", 1: "run", 2: "manual", 3: "fault", 4: "excite"}
FAULT_HISTORY_ADDRESS, ENTRY_WORDS, ENTRIES = 200, 10, 8  # registers/epa.csv: input 200-281


class Rig:
    """The appliance, a heartbeat thread and a resetter thread, each on its own Modbus connection
    (the appliance's own client is used by the test itself)."""

    def __init__(self, app):
        self.app = app
        self.lock = threading.Lock()
        self.stop = False
        self.beating = threading.Event()
        self.beating.set()
        self.beat = 0
        self.latched_ms = []  # per fault: from reading fault_active = 1 to reading it 0 again
        self.threads = [threading.Thread(target=self._heartbeat, daemon=True), threading.Thread(target=self._resetter, daemon=True)]
        for t in self.threads:
            t.start()

    def _client(self):
        c = ModbusTcpClient(HOST, port=self.app.port, timeout=2, retries=1)
        if not c.connect():
            raise RuntimeError("pymodbus could not connect")
        return c

    def _heartbeat(self):
        c = self._client()
        while not self.stop:
            if self.beating.is_set():
                self.beat += 1
                c.write_registers(6, u32_words(self.beat), slave=UNIT)
            time.sleep(0.05)
        c.close()

    def _resetter(self):
        """As fast as a client can: polls fault_active and writes reset (coil 0) as soon as it reads 1,
        once; notes how long the fault stayed visible."""
        c = self._client()
        seen_at = None
        while not self.stop:
            rr = c.read_discrete_inputs(0, 1, slave=UNIT)
            if rr.isError():
                continue
            if rr.bits[0] and seen_at is None:
                seen_at = time.monotonic()
                c.write_coil(0, True, slave=UNIT)
            elif not rr.bits[0] and seen_at is not None:
                self.latched_ms.append((time.monotonic() - seen_at) * 1000)
                seen_at = None
        c.close()

    def write(self, address, words):
        with self.lock:
            rr = self.app.client.write_registers(address, words, slave=UNIT)
        if rr.isError():
            raise RuntimeError(f"write holding {address} {words}: {rr}")

    def inputs(self, address, count):
        with self.lock:
            rr = self.app.client.read_input_registers(address, count, slave=UNIT)
        if rr.isError():
            raise RuntimeError(f"read input {address}+{count}: {rr}")
        return rr.registers

    def mode(self):
        with self.lock:
            return self.app.client.read_holding_registers(2, 1, slave=UNIT).registers[0]

    def faults_counter(self):
        return u32_value(self.inputs(114, 2))  # `faults`: latched since start

    def position(self):
        return f32_value(self.inputs(0, 2), "ABCD")

    def close(self):
        self.stop = True
        for t in self.threads:
            t.join(timeout=5)


def http_json(app, path):
    with urllib.request.urlopen(f"http://{HOST}:{app.web_port}{path}", timeout=5) as r:
        return json.loads(r.read())


def main():
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    epa, src = sys.argv[1], sys.argv[2]
    check = Checks()
    failures = check.failures

    app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), CONFIG, web_static_dir=os.path.join(src, "web"))
    rig = Rig(app)
    started_s = time.time()
    caused = []  # (name, mode, setpoint) in the order caused
    try:
        # 1: following-error in RUN. Plain PP (controller 0) and RUN (which holds the piston), then a
        # setpoint 10 mm above it, which PP's output never drives past the valve's dead band: the
        # piston stands, the motion a move is expected to make leaves it behind, and 10 ms after the
        # gap passed 5 mm the loop faults.
        start_mm = rig.position()
        target = start_mm + 10.0
        before = rig.faults_counter()
        rig.write(3, [0])
        rig.write(2, [1])
        rig.write(0, f32_words(target, "ABCD"))
        check(wait_until(lambda: rig.faults_counter() == before + 1, 3.0), "following-error: latched")
        check(wait_until(lambda: rig.mode() == 0, 2.0), "following-error: reset to STOP at once by the second client")
        caused.append(("following-error", "run", target))

        # 2: heartbeat-lost in MANUAL, the valve at its safe command: the heartbeat stops for 0.3 s.
        wait_until_steady(rig.position, 0.05, 5.0)  # the piston comes to rest (bounded)
        before = rig.faults_counter()
        rig.write(2, [2])
        wait_until(lambda: rig.mode() == 2, 2.0)  # MANUAL taken before the heartbeat stops
        rig.beating.clear()
        check(wait_until(lambda: rig.faults_counter() == before + 1, 3.0), "heartbeat-lost: latched")
        rig.beating.set()
        check(wait_until(lambda: rig.mode() == 0, 2.0), "heartbeat-lost: reset to STOP at once by the second client")
        caused.append(("heartbeat-lost", "manual", target))
        position_before_soft_limit = rig.position()

        # 3: soft-limit in MANUAL: 1.5 V (beyond the dead zone) drives the piston up past soft_max_mm.
        wait_until_steady(rig.position, 0.05, 5.0)  # at rest again (bounded)
        before = rig.faults_counter()
        rig.write(2, [2])
        check(wait_until(lambda: rig.mode() == 2, 2.0), "soft-limit: MANUAL")
        rig.write(4, f32_words(MANUAL_V, "ABCD"))
        check(wait_until(lambda: rig.faults_counter() == before + 1, 10.0), "soft-limit: latched")
        check(wait_until(lambda: rig.mode() == 0, 2.0), "soft-limit: reset to STOP at once by the second client")
        caused.append(("soft-limit", "manual", target))
        # The supervisor drains the ring every 50 ms and the store thread writes it at once; the
        # resetting client has timed the third fault (bounded wait; the checks below judge).
        wait_until(lambda: len(rig.latched_ms) == 3 and http_json(app, "/api/faults")["count"] == 3, 5.0, 0.05)
        shown = ", ".join(f"{ms:.1f}" for ms in rig.latched_ms)
        check(len(rig.latched_ms) == 3 and max(rig.latched_ms) < 50.0,
              f"each fault was visible to the resetting client for less than the supervisor's 50 ms tick: {shown} ms")

        expected = list(reversed(caused))  # newest first
        codes = {"following-error": 6, "heartbeat-lost": 7, "soft-limit": 3}
        mode_numbers = {"run": 1, "manual": 2}

        # ---- GET /api/faults ----
        d = http_json(app, "/api/faults")
        check(d["count"] == 3, f"/api/faults count {d['count']} == 3")
        got = [(f["name"], f["mode"]) for f in d["faults"]]
        check(got == [(n, m) for n, m, _ in expected], f"/api/faults newest first: {got}")
        for f, (name, mode, setpoint) in zip(d["faults"], expected):
            check(f["code"] == codes[name], f"{name}: code {f['code']}")
            check(f["text"] and "no fault" not in f["text"], f"{name}: text '{f['text']}'")
            check(abs(f["setpoint_mm"] - setpoint) < 0.01, f"{name}: setpoint {f['setpoint_mm']} mm == {setpoint:.2f}")
            check(started_s - 1 <= f["time_ms"] / 1000 <= time.time() + 1, f"{name}: time {f['time']} within the test")
            check(re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z", f["time"]) is not None, f"{name}: ISO 8601 UTC time {f['time']}")
            check(f["sensor_v"] is not None and f["valve_v"] is not None, f"{name}: valve and sensor recorded")
        soft, heart, follow = d["faults"]
        check(soft["position_mm"] > SOFT_MAX_MM and soft["position_mm"] < SOFT_MAX_MM + 20,
              f"soft-limit: position {soft['position_mm']:.2f} mm just past soft_max_mm {SOFT_MAX_MM}")
        check(abs(soft["valve_v"] - MANUAL_V) < 1e-6, f"soft-limit: valve {soft['valve_v']} V, the manual command driving it")
        check(abs(heart["valve_v"]) < 1e-6, f"heartbeat-lost: valve {heart['valve_v']} V (MANUAL at the safe command)")
        check(abs(heart["position_mm"] - position_before_soft_limit) < 5.0,
              f"heartbeat-lost: position {heart['position_mm']:.2f} mm where the piston stood")
        check(abs(follow["position_mm"] - start_mm) < 1.0 and follow["position_mm"] < follow["setpoint_mm"] - 5.0,
              f"following-error: position {follow['position_mm']:.2f} mm, standing at {start_mm:.2f} mm and more than "
              f"5 mm short of setpoint {follow['setpoint_mm']:.2f}")
        check(soft["time_ms"] > heart["time_ms"] > follow["time_ms"], "the times are in the order the faults happened")

        # ---- Modbus: fault_history_count and the newest entries ----
        words = rig.inputs(FAULT_HISTORY_ADDRESS, 2 + ENTRY_WORDS * ENTRIES)
        check(u32_value(words[0:2]) == 3, f"Modbus fault_history_count {u32_value(words[0:2])} == 3")
        for i in range(ENTRIES):
            w = words[2 + ENTRY_WORDS * i: 2 + ENTRY_WORDS * (i + 1)]
            code, mode, t = w[0], w[1], u32_value(w[2:4])
            pos, sp, valve = f32_value(w[4:6], "ABCD"), f32_value(w[6:8], "ABCD"), f32_value(w[8:10], "ABCD")
            if i < 3:
                f = d["faults"][i]
                check(code == f["code"] and MODES.get(mode) == f["mode"],
                      f"Modbus entry {i}: code {code}, mode {mode} == {f['name']} in {f['mode']}")
                check(t == f["time_ms"] // 1000, f"Modbus entry {i}: time {t} == {f['time_ms'] // 1000} (unix s)")
                check(abs(pos - f["position_mm"]) < 1e-3 and abs(sp - f["setpoint_mm"]) < 1e-3 and abs(valve - f["valve_v"]) < 1e-5,
                      f"Modbus entry {i}: position {pos:.3f}, setpoint {sp:.3f} mm, valve {valve:.4f} V as /api/faults")
            else:
                check(code == 0 and math.isnan(pos) and math.isnan(sp) and math.isnan(valve) and mode == 0xFFFF and t == 0xFFFFFFFF,
                      f"Modbus entry {i}: an empty slot (code {code}, mode {mode}, time {t}, {pos}, {sp}, {valve})")

        # ---- epa faults, while the appliance runs ----
        out = subprocess.run([epa, "faults", "--store", app.db, "--json"], capture_output=True, text=True, timeout=30)
        check(out.returncode == 0, f"epa faults --json exits 0 ({out.stderr.strip()})")
        cli = json.loads(out.stdout) if out.returncode == 0 else {"count": None, "faults": []}
        check(cli["count"] == 3 and cli["faults"] == d["faults"], f"epa faults --json is what /api/faults says: {cli}")
        out = subprocess.run([epa, "faults", "--store", app.db, "--limit", "2"], capture_output=True, text=True, timeout=30)
        lines = [l for l in out.stdout.splitlines() if re.match(r"\d{4}-", l)]
        check(out.returncode == 0 and len(lines) == 2 and "soft-limit" in lines[0] and "in manual" in lines[0]
              and "heartbeat-lost" in lines[1], f"epa faults --limit 2 lists the newest two:\n{out.stdout}")
        check(out.stdout.startswith("3 faults since the store was created"), "epa faults says how many")

        # ---- the log ----
        log = app.log_text()
        check("FAULT none" not in log, "the log has no 'FAULT none'")
        fault_lines = re.findall(r"FAULT ([a-z-]+): .* \(in ([a-z]+), position ([-0-9.]+) mm, setpoint ([-0-9.]+) mm, valve ([-0-9.]+) V", log)
        check([(n, m) for n, m, *_ in fault_lines] == [(n, m) for n, m, _ in caused],
              f"the log's FAULT lines name each cause and mode in order: {fault_lines}")
    except Exception:
        print(f"---- appliance log ----\n{app.log_text()}")
        raise
    finally:
        rig.close()
        status = app.stop()
    check(status == 0, f"epa serve stopped cleanly (status {status})")

    # ---- after a restart, the history is still there ----
    app.start()
    try:
        d2 = http_json(app, "/api/faults")
        check(d2["count"] == 3 and [f["name"] for f in d2["faults"]] == [n for n, _, _ in reversed(caused)],
              f"after a restart /api/faults still lists the three: {[f['name'] for f in d2['faults']]}")
        words = app.client.read_input_registers(FAULT_HISTORY_ADDRESS, 3, slave=UNIT).registers
        check(u32_value(words[0:2]) == 3 and words[2] == 3, f"after a restart Modbus reads count {u32_value(words[0:2])}, newest code {words[2]}")
    finally:
        app.stop()
    if failures:
        print(f"---- appliance log ----\n{app.log_text()}")
        app.remove()
        print(f"{len(failures)} check(s) failed")
        return 1
    app.remove()
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
