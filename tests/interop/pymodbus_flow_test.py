#!/usr/bin/env python3
"""Interoperability, the whole integration: what a SCADA/HMI integrator does with Debian's
python3-pymodbus 3.0 (the sync TCP client) against one running appliance on the simulated plant.

    pymodbus_flow_test.py <epa binary> <source dir>

`epa serve` on a free loopback port ([limits] soft_max_mm = 300 so that a fault can be caused,
heartbeat_timeout_s = 5 with a heartbeat thread on its own connection, as an HMI keeps one),
stopped by its PID at the end (terminate, kill after 5 s). The steps run in order on one
appliance (test_1_..., test_8_...); a failed step makes the later ones skip:
  1 the register map as an integrator gets it (`epa registers --csv`): every point used here is
    looked up by name there (table, address, type, ABCD word order), nothing else is assumed;
  2 FC43/14 device identification: MajorMinorRevision is what `epa --version` prints;
  3 enable: mode RUN (FC6) holds the piston: ready, run_enabled, in_position;
  4 a position record: unlock (key64, FC16), record 1 written whole in one FC16 and read back,
    record_select 1;
  5 the start/acknowledge handshake: start=1, ack=1 (with moving or in_position), start=0,
    ack=0, then in_position with target_reached at the record's target, move_end complete;
  6 halt: record 2 (speed-limited) started, halted mid-way: halted, move_end halted, the piston
    stands short of the target, not moving and not in position (that is the target's);
  7 jog in MANUAL: jog_plus held (control word rewritten as a keep-alive) moves up at about
    jog_speed_mm_s, release brakes; jog_minus (the coil) with the client gone silent (no control
    word write, no heartbeat) brakes by itself after jog_keepalive_s;
  8 the fault history: MANUAL valve 1.5 V drives the piston past 300 mm: soft-limit fault
    (mode 3, fault_latched, fault_code 3), reset with the control word's reset bit (rising edge),
    then fault_history_count is one more and the newest entry is that fault (code, mode manual,
    time, position, valve).
Each step prints how long it took. Exit 0 when every step passes, 1 otherwise.
"""
import csv
import io
import math
import os
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import (UNIT, Appliance, Heartbeat, f32_value, f32_words, pymodbus, u32_value,  # noqa: E402
                           unlock)
from pymodbus.mei_message import ReadDeviceInformationRequest  # noqa: E402

EPA = None  # the binary and the source dir, from the command line
SRC = None
SOFT_MAX_MM = 300.0
CONFIG = ("[limits]\n"
          f"soft_max_mm = {SOFT_MAX_MM}\n"
          "setpoint_max_mm = 290.0\n"   # the setpoint range must lie inside the soft limits
          "heartbeat_timeout_s = 5.0\n")  # generous: a test starved for a moment on a loaded machine
JOG_SPEED_MM_S = 20.0     # [motion] jog_speed_mm_s, the default
JOG_KEEPALIVE_S = 1.0     # [motion] jog_keepalive_s, the default

# status_word (input 140) bits, as the map's description lists them
READY, RUN_ENABLED, MOVING, IN_POSITION, TARGET_REACHED, FOLLOWING_ERROR, WARNING, FAULT_LATCHED, ACK, HALTED, \
    JOGGING, MANUAL_MODE, OFF_TARGET = (1 << i for i in range(13))
BIT_NAMES = ["ready", "run_enabled", "moving", "in_position", "target_reached", "following_error", "warning",
             "fault_latched", "ack", "halted", "jogging", "manual_mode", "off_target"]
# control_word (holding 50) bits
START, HALT, JOG_PLUS, JOG_MINUS, RESET = (1 << i for i in range(5))
MOVE_COMPLETE, MOVE_CUT_SHORT, MOVE_HALTED = 0, 1, 2


def bits(word):
    return ",".join(n for i, n in enumerate(BIT_NAMES) if word >> i & 1) or "-"


class FlowTest(unittest.TestCase):
    """One appliance for the whole flow; the steps run in name order."""

    app = None
    hb = None
    broken = False  # a step failed: the later ones skip (they build on it)
    p = None        # point name -> row of the exported map

    @classmethod
    def setUpClass(cls):
        cls.app = Appliance(EPA, os.path.join(SRC, "registers/epa.csv"), CONFIG)
        cls.c = cls.app.client
        cls.hb = Heartbeat(cls.app.port)

    @classmethod
    def tearDownClass(cls):
        status = None
        try:
            cls.hb.close()
            status = cls.app.stop()
            if cls.broken:
                print(f"\n---- appliance log ----\n{cls.app.log_text()}---- end of log ----", file=sys.stderr)
        finally:
            cls.app.remove()
        if status != 0:
            raise AssertionError(f"epa serve exited with status {status} after SIGTERM, expected 0")

    def setUp(self):
        if type(self).broken:
            self.skipTest("an earlier step failed")

    def run(self, result=None):
        before = len(result.errors) + len(result.failures) if result else 0
        out = super().run(result)
        if result and len(result.errors) + len(result.failures) > before:
            type(self).broken = True
        return out

    # ---- the map: addresses by point name ----
    def at(self, name, table, type_=None):
        row = self.p.get((name, table))
        self.assertIsNotNone(row, f"point {name} ({table}) in the exported map")
        self.assertEqual(row["table"], table, f"{name}: table")
        if type_:
            self.assertEqual(row["type"], type_, f"{name}: type")
        if row["type"] in ("float32", "uint32"):
            self.assertEqual(row["word_order"], "ABCD", f"{name}: word order")
        return int(row["address"])

    # ---- Modbus, every answer checked ----
    def ok(self, rr, what):
        self.assertFalse(rr.isError(), f"{what}: expected a normal response, got {rr}")
        return rr

    def holding(self, name, count=1):
        a = self.at(name, "holding")
        return self.ok(self.c.read_holding_registers(a, count, slave=UNIT), f"read {name}").registers

    def inputs(self, name, count=1):
        a = self.at(name, "input")
        return self.ok(self.c.read_input_registers(a, count, slave=UNIT), f"read {name}").registers

    def write(self, name, value):
        """FC6 for a 16-bit point, FC16 for a float (ABCD)."""
        a = self.at(name, "holding")
        row = self.p[(name, "holding")]
        if row["type"] == "float32":
            return self.ok(self.c.write_registers(a, f32_words(value, "ABCD"), slave=UNIT), f"write {name} {value}")
        return self.ok(self.c.write_register(a, value, slave=UNIT), f"write {name} {value}")

    def f32(self, name, table="input"):
        regs = self.inputs(name, 2) if table == "input" else self.holding(name, 2)
        return f32_value(regs, "ABCD")

    def status(self):
        return self.inputs("status_word")[0]

    def wait_status(self, want, timeout_s, what, clear=0, since=None):
        """Polls status_word every 10 ms until all of `want` are set and all of `clear` are clear;
        returns (word, seconds since `since`)."""
        since = since or time.monotonic()
        deadline = time.monotonic() + timeout_s
        word = None
        while time.monotonic() < deadline:
            word = self.status()
            if word & want == want and not word & clear:
                return word, time.monotonic() - since
            time.sleep(0.01)
        self.fail(f"{what}: status_word did not have {bits(want)} set and {bits(clear)} clear within {timeout_s} s; "
                  f"last {word:#06x} ({bits(word)}), position {self.f32('position_mm'):.2f} mm, mode {self.holding('mode')[0]}")

    def wait_standing(self, timeout_s, what):
        """Until two position reads 0.3 s apart agree within 0.2 mm."""
        deadline = time.monotonic() + timeout_s
        last = self.f32("position_mm")
        while time.monotonic() < deadline:
            time.sleep(0.3)
            now = self.f32("position_mm")
            if abs(now - last) <= 0.2:
                return now
            last = now
        self.fail(f"{what}: the piston did not stand still within {timeout_s} s (last {last:.2f} mm)")

    def say(self, text):
        print(f"\n  {text}", end="", file=sys.stderr)

    def start_handshake(self, what):
        """start=1, wait ack (and moving or in_position), start=0, wait ack=0; returns the word with ack."""
        t0 = time.monotonic()
        self.write("control_word", START)
        word, t_ack = self.wait_status(ACK, 2.0, f"{what}: ack after start=1", since=t0)
        self.assertTrue(word & (MOVING | IN_POSITION), f"{what}: ack without moving or in_position: {bits(word)}")
        self.assertFalse(word & TARGET_REACHED, f"{what}: target_reached still set once the start is acknowledged: "
                                                f"{bits(word)}")
        t1 = time.monotonic()
        self.write("control_word", 0)
        _, t_clear = self.wait_status(0, 2.0, f"{what}: ack clears after start=0", clear=ACK, since=t1)
        self.say(f"{what}: ack {t_ack * 1000:.0f} ms after start=1 ({bits(word)}), "
                 f"cleared {t_clear * 1000:.0f} ms after start=0")
        return t0

    # ---- the flow ----
    def test_1_register_map(self):
        out = subprocess.run([EPA, "registers", os.path.join(SRC, "registers/epa.csv"), "--csv", "-"],
                             capture_output=True, text=True, timeout=30)
        self.assertEqual(out.returncode, 0, f"epa registers --csv: {out.stderr}")
        rows = list(csv.DictReader(io.StringIO(out.stdout)))
        type(self).p = {(r["point"], r["table"]): r for r in rows}  # `reset` is a holding register and a coil
        self.say(f"map: {len(rows)} points exported by `epa registers --csv`")
        for name, table, type_ in [("setpoint_mm", "holding", "float32"), ("mode", "holding", "uint16"),
                                   ("manual_valve_v", "holding", "float32"), ("heartbeat", "holding", "uint32"),
                                   ("unlock", "holding", "key64"), ("control_word", "holding", "uint16"),
                                   ("record_select", "holding", "uint16"), ("record1_target_mm", "holding", "float32"),
                                   ("record1_controller", "holding", "uint16"), ("position_mm", "input", "float32"),
                                   ("fault_code", "input", "uint16"), ("status_word", "input", "uint16"),
                                   ("move_end", "input", "uint16"), ("speed_mm_s", "input", "float32"),
                                   ("fault_history_count", "input", "uint32"), ("fault_0_code", "input", "uint16"),
                                   ("fault_0_valve_v", "input", "float32")]:
            self.at(name, table, type_)
        # What the shared heartbeat helper and the record layout assume (docs: 1000 + 8 (N-1)).
        self.assertEqual(self.at("heartbeat", "holding"), self.hb.address, "heartbeat address")
        self.assertEqual(self.at("record2_target_mm", "holding") - self.at("record1_target_mm", "holding"), 8)
        self.assertEqual([self.at(f"record1_{f}", "holding") - self.at("record1_target_mm", "holding")
                          for f in ("speed_mm_s", "window_mm", "controller")], [2, 4, 6], "record 1 layout")
        self.assertEqual([self.at(f"fault_0_{f}", "input") - self.at("fault_0_code", "input")
                          for f in ("mode", "time_s", "position_mm", "setpoint_mm", "valve_v")], [1, 2, 4, 6, 8],
                         "fault history entry layout")
        self.assertEqual(self.at("fault_1_code", "input") - self.at("fault_0_code", "input"), 10, "entry size")

    def test_2_device_identification(self):
        version = subprocess.run([EPA, "--version"], capture_output=True, text=True, timeout=10).stdout.strip()
        self.assertRegex(version, r"^epa \d+\.\d+\.\d+$")
        rr = self.ok(self.c.execute(ReadDeviceInformationRequest(read_code=0x01, object_id=0x00, unit=UNIT)),
                     "FC43/14 read code 01")
        self.say(f"FC43/14: {rr.information}")
        self.assertEqual(rr.information.get(0x02), version.split()[1].encode(), "MajorMinorRevision = epa --version")
        self.assertEqual(rr.information.get(0x01), b"epa", "ProductCode")

    def test_3_enable(self):
        word = self.status()
        self.assertEqual(word & (READY | RUN_ENABLED | FAULT_LATCHED), READY, f"at start: {bits(word)}")
        t0 = time.monotonic()
        self.write("mode", 1)
        word, t = self.wait_status(READY | RUN_ENABLED | IN_POSITION, 2.0, "mode RUN", clear=MOVING, since=t0)
        self.assertEqual(self.holding("mode")[0], 1)
        self.assertLessEqual(abs(self.f32("position_mm")), 1.0, "RUN holds the piston where it is (0 mm)")
        self.say(f"enable: run_enabled and in_position {t * 1000:.0f} ms after mode 1 ({bits(word)})")

    def test_4_position_record(self):
        self.ok(unlock(self.c), "unlock with the configured key (FC16, 4 registers)")
        base = self.at("record1_target_mm", "holding")
        words = f32_words(150.0, "ABCD") + f32_words(0.0, "ABCD") + f32_words(2.0, "ABCD") + [255]
        self.ok(self.c.write_registers(base, words, slave=UNIT), "record 1 (target 150, speed 0, window 2, law 255) in one FC16")
        back = self.ok(self.c.read_holding_registers(base, 7, slave=UNIT), "read record 1").registers
        self.assertEqual(back, words, "record 1 reads back as written")
        base2 = self.at("record2_target_mm", "holding")
        words2 = f32_words(40.0, "ABCD") + f32_words(60.0, "ABCD") + f32_words(0.0, "ABCD") + [3]
        self.ok(self.c.write_registers(base2, words2, slave=UNIT), "record 2 (target 40, speed 60 mm/s, law 3 pp-traj: made for a profile) in one FC16")
        self.write("record_select", 1)
        self.assertEqual(self.holding("record_select")[0], 1)

    def test_5_start_handshake(self):
        t0 = self.start_handshake("start record 1")
        word, t = self.wait_status(IN_POSITION | TARGET_REACHED, 15.0, "record 1: in_position with target_reached",
                                   clear=MOVING | ACK, since=t0)
        position = self.f32("position_mm")
        self.assertLessEqual(abs(position - 150.0), 2.0, "in position within record 1's 2 mm window")
        self.assertEqual(self.inputs("move_end")[0], MOVE_COMPLETE, "move_end: complete")
        self.assertEqual(self.holding("mode")[0], 1, "still RUN")
        self.say(f"record 1: in_position + target_reached {t:.2f} s after start=1, at {position:.2f} mm ({bits(word)})")

    def test_6_halt(self):
        self.write("record_select", 2)
        t0 = self.start_handshake("start record 2")
        # Halfway down (150 -> 40 mm at 60 mm/s: about 1.8 s), halt.
        deadline = time.monotonic() + 5.0
        while self.f32("position_mm") > 110.0 and time.monotonic() < deadline:
            time.sleep(0.02)
        at_halt = self.f32("position_mm")
        self.assertLess(at_halt, 125.0, "record 2 moves down before the halt")
        t1 = time.monotonic()
        self.write("control_word", HALT)
        word, t_halted = self.wait_status(HALTED, 2.0, "halted after halt=1", since=t1)
        # Stood where it braked to, short of the record's target: halted, and not in position (that is
        # the target's).
        word, t_stand = self.wait_status(HALTED, 5.0, "halted and standing short of the target, not in position",
                                         clear=MOVING | IN_POSITION, since=t1)
        self.write("control_word", 0)
        rest = self.wait_standing(5.0, "after the halt")
        self.assertEqual(self.inputs("move_end")[0], MOVE_HALTED, "move_end: halted")
        self.assertFalse(word & TARGET_REACHED, f"target_reached after a halt: {bits(word)}")
        self.assertGreater(rest, 55.0, f"the piston stopped short of record 2's 40 mm (halted at {at_halt:.2f} mm)")
        self.assertLessEqual(abs(rest - self.f32("reference_mm")), 2.0, "it holds where the reference stopped")
        self.assertEqual(self.holding("mode")[0], 1, "still RUN")
        self.say(f"halt at {at_halt:.2f} mm ({time.monotonic() - t0:.2f} s into the move): halted after "
                 f"{t_halted * 1000:.0f} ms, standing {t_stand:.2f} s after halt=1 at {rest:.2f} mm, not in position")

    def test_7_jog(self):
        t0 = time.monotonic()
        self.write("mode", 2)
        word, t = self.wait_status(MANUAL_MODE | READY, 2.0, "MANUAL", clear=RUN_ENABLED, since=t0)
        self.say(f"MANUAL {t * 1000:.0f} ms after mode 2 ({bits(word)})")
        start = self.wait_standing(5.0, "before the jog")
        # jog_plus held for 1.5 s; the control word rewritten every 0.3 s (the keep-alive).
        t0 = time.monotonic()
        self.write("control_word", JOG_PLUS)
        word, t_jog = self.wait_status(JOGGING | MOVING, 2.0, "jogging after jog_plus", since=t0)
        speeds = []
        while time.monotonic() - t0 < 1.5:
            time.sleep(0.3)
            self.write("control_word", JOG_PLUS)
            speeds.append(self.f32("speed_mm_s"))
        self.write("control_word", 0)
        t1 = time.monotonic()
        _, t_brake = self.wait_status(MANUAL_MODE, 2.0, "jog released: jogging clears", clear=JOGGING | MOVING, since=t1)
        end = self.wait_standing(5.0, "after releasing jog_plus")
        top = max(speeds)
        self.assertTrue(0.5 * JOG_SPEED_MM_S <= top <= 1.5 * JOG_SPEED_MM_S,
                        f"jog speed about {JOG_SPEED_MM_S} mm/s: read {['%.1f' % s for s in speeds]}")
        self.assertGreater(end - start, 15.0, f"jog_plus for 1.5 s moved the piston up ({start:.2f} -> {end:.2f} mm)")
        self.say(f"jog_plus: jogging {t_jog * 1000:.0f} ms after the write, top speed {top:.1f} mm/s, "
                 f"{start:.2f} -> {end:.2f} mm, braked {t_brake * 1000:.0f} ms after release")
        # jog_minus through its coil, then silence: no control word write, no heartbeat.
        self.hb.pause()
        try:
            t0 = time.monotonic()
            self.ok(self.c.write_coil(self.at("jog_minus", "coil"), True, slave=UNIT), "coil jog_minus 1")
            self.wait_status(JOGGING | MOVING, 2.0, "jogging after coil jog_minus", since=t0)
            _, t_lapse = self.wait_status(MANUAL_MODE, JOG_KEEPALIVE_S + 2.0,
                                          "jog_minus without keep-alive brakes by itself", clear=JOGGING | MOVING, since=t0)
        finally:
            self.hb.resume()
        self.ok(self.c.write_coil(self.at("jog_minus", "coil"), False, slave=UNIT), "coil jog_minus 0")
        below = self.wait_standing(5.0, "after the keep-alive lapsed")
        self.assertGreaterEqual(t_lapse, JOG_KEEPALIVE_S - 0.05, "not before jog_keepalive_s")
        self.assertLess(below, end, "jog_minus moved the piston down")
        self.assertEqual(self.holding("mode")[0], 2, "still MANUAL (a lapsed jog brakes, it does not fault)")
        self.say(f"jog_minus (coil) with the client silent: braked {t_lapse:.2f} s after the write, at {below:.2f} mm")

    def test_8_fault_history(self):
        count_before = u32_value(self.inputs("fault_history_count", 2))
        self.assertEqual(self.holding("mode")[0], 2, "MANUAL")
        t0 = time.monotonic()
        self.write("manual_valve_v", 1.5)
        word, t_fault = self.wait_status(FAULT_LATCHED, 15.0, f"soft-limit fault (piston past {SOFT_MAX_MM} mm)",
                                         since=t0)
        self.assertFalse(word & READY, f"ready while a fault is latched: {bits(word)}")
        self.assertEqual(self.holding("mode")[0], 3, "mode 3 (fault)")
        self.assertEqual(self.inputs("fault_code")[0], 3, "fault_code 3 (soft limit)")
        self.assertEqual(self.ok(self.c.read_discrete_inputs(self.at("fault_latched", "discrete"), 1, slave=UNIT),
                                 "discrete fault_latched").bits[0], True, "discrete input fault_latched")
        # Reset through the control word: a rising edge of bit 4, then the bit back to 0.
        t1 = time.monotonic()
        self.write("control_word", RESET)
        word, t_reset = self.wait_status(READY, 2.0, "ready after the reset bit", clear=FAULT_LATCHED, since=t1)
        self.write("control_word", 0)
        self.assertEqual(self.holding("mode")[0], 0, "mode 0 (stop) after the reset")
        self.assertEqual(self.inputs("fault_code")[0], 0, "fault_code cleared")
        # An HMI reads the history when the fault is gone (ready again): it should hold the fault then.
        count_at_ready = u32_value(self.inputs("fault_history_count", 2))
        t2 = time.monotonic()
        count = count_at_ready
        while count == count_before and time.monotonic() - t2 < 2.0:
            time.sleep(0.005)
            count = u32_value(self.inputs("fault_history_count", 2))
        lag_ms = (time.monotonic() - t2) * 1000
        self.assertEqual(count, count_before + 1, "fault_history_count (waited up to 2 s)")
        e = self.inputs("fault_0_code", 10)
        code, mode, when = e[0], e[1], u32_value(e[2:4])
        position, setpoint, valve = (f32_value(e[i:i + 2], "ABCD") for i in (4, 6, 8))
        self.assertEqual(code, 3, "newest entry: code 3 (soft limit)")
        self.assertEqual(mode, 2, "newest entry: mode before the fault 2 (manual)")
        self.assertLessEqual(abs(when - time.time()), 60, f"newest entry: time {when} is now")
        self.assertTrue(SOFT_MAX_MM - 1.0 <= position <= SOFT_MAX_MM + 10.0, f"newest entry: position {position}")
        self.assertTrue(math.isfinite(setpoint), f"newest entry: setpoint {setpoint}")
        self.assertAlmostEqual(valve, 1.5, places=3, msg="newest entry: valve 1.5 V")
        self.say(f"fault: soft-limit latched {t_fault:.2f} s after valve 1.5 V, reset bit -> ready in "
                 f"{t_reset * 1000:.0f} ms; history count at ready {count_at_ready}, {count} after {lag_ms:.0f} ms; newest: code {code}, mode {mode}, time {when}, "
                 f"position {position:.2f} mm, setpoint {setpoint:.2f} mm, valve {valve:.3f} V")
        self.assertEqual(self.hb.errors, [], "every heartbeat write answered")
        self.assertEqual(count_at_ready, count_before + 1,
                         f"DEVICE: fault_history_count read right after the reset (status ready, mode 0) was still "
                         f"{count_at_ready}; the reset fault was counted {lag_ms:.0f} ms later (the reset bit was written "
                         f"{(t1 - t0 - t_fault) * 1000:.0f} ms after fault_latched was read)")


def main():
    global EPA, SRC
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    EPA, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if not os.access(EPA, os.X_OK):
        sys.exit(f"FAIL: {EPA} is not an executable")
    print(f"pymodbus {pymodbus.__version__}, python {sys.version.split()[0]}", file=sys.stderr)
    suite = unittest.TestLoader().loadTestsFromTestCase(FlowTest)
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    sys.exit(0 if result.wasSuccessful() and not result.skipped else 1)


if __name__ == "__main__":
    main()
