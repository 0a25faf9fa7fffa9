#!/usr/bin/env python3
"""Interoperability: Debian's python3-pymodbus 3.0 (the sync TCP client) against a running appliance.

    pymodbus_test.py <epa binary> <source dir>

Starts `epa serve` on the simulated plant twice, each on a free loopback port, stops each by its
PID (terminate, kill after 5 s):
  * with registers/epa.csv: every mapped table (coils, discrete inputs, holding, input registers)
    is read whole and its values checked, every writable table is written (coil reset, setpoint
    as an ABCD float through FC16, mode through FC6, heartbeat, unlock and the tuning register
    lc_mm, FC23 read/write), the writes take effect (read back; the piston moves), and each
    refusal comes back with the exception code request_handler.hpp documents; FC43/14 device
    identification (basic, regular, one object) names the version `epa --version` prints, unit
    id 0 is answered as this device, and the bit tables read in blocks of 8 and 16;
  * with registers/examples/legacy-hmi.csv: the word-swapped (CDAB) float copies at 1010-1011
    decode to the same values as the scaled int16 copies at 1000 (position x10, setpoint x10),
    written either way.
Floats are decoded here with struct in an explicit word order, not with pymodbus' payload helpers.
Exit 0 when every test passes, 1 otherwise (unittest prints "Ran N tests ... OK/FAILED").
"""
import math
import os
import re
import subprocess
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import (UNIT, UNLOCK_ADDRESS, Appliance, unlock, f32_value, f32_words, i16_value, pymodbus,  # noqa: E402
                           u32_value, u32_words)
from pymodbus.mei_message import ReadDeviceInformationRequest  # noqa: E402

VERSION = None  # (major, minor, patch) as `epa --version` prints it: CMakeLists.txt's project(VERSION)
MM_PER_VOLT = 50.0   # the paper's position sensor scale (config/paper-model.toml)
HEARTBEAT_TIMEOUT_S = 5.0  # [limits] heartbeat_timeout_s of the epa.csv appliance: generous, so a test
# process starved for a moment on a loaded CI machine does not lapse it by accident

ILLEGAL_ADDRESS, ILLEGAL_VALUE, CANNOT_APPLY, OTHER_UNIT = 0x02, 0x03, 0x04, 0x0B
BASIC, REGULAR, EXTENDED, SPECIFIC = 0x01, 0x02, 0x03, 0x04  # FC43/14 read device id codes

EPA = None  # the binary and the source dir, from the command line
SRC = None


# ---- common test machinery ----
class ApplianceTest(unittest.TestCase):
    REGISTER_MAP = None  # relative to the source dir
    EXTRA_CONFIG = ""
    STATUS_PAGE = False  # the status page on a free port too (FC43's VendorUrl names it)
    app = None

    @classmethod
    def setUpClass(cls):
        cls.app = Appliance(EPA, os.path.join(SRC, cls.REGISTER_MAP), cls.EXTRA_CONFIG,
                            web_static_dir=os.path.join(SRC, "web") if cls.STATUS_PAGE else None)
        cls.c = cls.app.client
        cls.failed = False

    @classmethod
    def tearDownClass(cls):
        try:
            status = cls.app.stop()
            if cls.failed:
                print(f"\n---- appliance log ({cls.REGISTER_MAP}) ----\n{cls.app.log_text()}---- end of log ----",
                      file=sys.stderr)
        finally:
            cls.app.remove()
        if status != 0:
            raise AssertionError(f"epa serve ({cls.REGISTER_MAP}) exited with status {status} after SIGTERM, expected 0")

    def run(self, result=None):
        errors = len(result.errors) + len(result.failures) if result else 0
        out = super().run(result)
        if result and len(result.errors) + len(result.failures) > errors:
            type(self).failed = True
        return out

    # Answers: a normal response, or an exception response with the expected code.
    def ok(self, rr, what):
        self.assertFalse(rr.isError(), f"{what}: expected a normal response, got {rr}")
        return rr

    def refused(self, rr, code, what):
        self.assertTrue(rr.isError(), f"{what}: expected exception {code:#04x}, got a normal response {rr}")
        self.assertEqual(getattr(rr, "exception_code", None), code,
                         f"{what}: expected exception {code:#04x}, got {rr}")

    def regs(self, fc, address, count, what=None):
        read = self.c.read_holding_registers if fc == 3 else self.c.read_input_registers
        what = what or f"FC{fc} {address} x{count}"
        rr = self.ok(read(address, count, slave=UNIT), what)
        self.assertEqual(len(rr.registers), count, f"{what}: register count")
        return rr.registers

    def device_information(self, read_code, object_id=0x00, unit=UNIT):
        """FC43/14: pymodbus 3.0's ReadDeviceInformationRequest (its sync client has no helper for it)."""
        return self.c.execute(ReadDeviceInformationRequest(read_code=read_code, object_id=object_id, unit=unit))

    def bit_table_ends(self, table):
        """A bit table of this map: (its last address + 1, where reads end: that rounded up to 16)."""
        end = 0
        with open(os.path.join(SRC, self.REGISTER_MAP)) as f:
            for line in f:
                fields = line.strip().split(",")
                if len(fields) > 2 and fields[1] == table:
                    end = max(end, int(fields[2]) + 1)
        return end, (end + 15) // 16 * 16

    def wait_until(self, predicate, timeout_s, what, every_s=0.1, tick=None, times=1):
        """Polls `predicate()` (returns (done, value)) until done `times` polls in a row, at most timeout_s."""
        deadline = time.monotonic() + timeout_s
        value = None
        in_a_row = 0
        while time.monotonic() < deadline:
            done, value = predicate()
            in_a_row = in_a_row + 1 if done else 0
            if in_a_row >= times:
                return value
            if tick:
                tick()
            time.sleep(every_s)
        self.fail(f"{what}: not within {timeout_s} s (last value {value})")


# ---- registers/epa.csv: every table, writes, exceptions ----
class EpaMapTest(ApplianceTest):
    """The appliance's own map. The tests run in name order on one appliance (test_1_..., test_2_...)."""

    REGISTER_MAP = "registers/epa.csv"
    # A supervising client must change the heartbeat in RUN; test_5 lets it lapse for a fault.
    EXTRA_CONFIG = f"[limits]\nheartbeat_timeout_s = {HEARTBEAT_TIMEOUT_S}\n"
    STATUS_PAGE = True

    # Input register blocks of epa.csv (address, count): each contiguous run of mapped registers.
    INPUT_BLOCKS = [(0, 11), (12, 3), (16, 2), (20, 42), (70, 14), (90, 14), (110, 17)]

    heartbeat = 0

    def beat(self):
        type(self).heartbeat += 1
        self.ok(self.c.write_registers(6, u32_words(self.heartbeat), slave=UNIT), "heartbeat write")

    def position(self):
        return f32_value(self.regs(4, 0, 2, "position_mm"), "ABCD")

    def mode(self):
        return self.regs(3, 2, 1, "mode")[0]

    def to_stop(self):
        self.ok(self.c.write_register(2, 0, slave=UNIT), "mode 0 (stop)")
        self.wait_until(lambda: (self.mode() == 0, self.mode()), 2.0, "mode reads 0 (stop)", every_s=0.02)

    def move_to(self, target, tol=3.0, timeout_s=15.0):
        # Three polls in a row within the band: the piston is there, not swinging through (FF-IDZ rings
        # on the paper's model, README "FF-IDZ overshoot").
        def check():
            p = self.position()
            return abs(p - target) <= tol, p
        return self.wait_until(check, timeout_s, f"position within {tol} mm of {target} (3 polls in a row)",
                               every_s=0.2, tick=self.beat, times=3)

    def test_1_read_every_table(self):
        # Coils: reset (reads 0).
        rr = self.ok(self.c.read_coils(0, 1, slave=UNIT), "read coil 0")
        self.assertEqual(rr.bits[:1], [False], "coil reset reads 0")
        # Discrete inputs: fault_active, saturated, io_ok, locked.
        rr = self.ok(self.c.read_discrete_inputs(0, 4, slave=UNIT), "read discrete inputs 0-3")
        self.assertGreaterEqual(len(rr.bits), 4)
        self.assertEqual(rr.bits[:4], [False, False, True, True], "fault_active, saturated, io_ok, locked at start")
        # Holding registers, both blocks whole.
        h = self.regs(3, 0, 15, "holding 0-14")
        self.assertEqual(f32_value(h[0:2], "ABCD"), 0.0, "setpoint_mm at start")
        self.assertEqual(h[2], 0, "mode: stop")
        self.assertEqual(h[3], 3, "controller: pp-traj (the default)")
        self.assertEqual(f32_value(h[4:6], "ABCD"), 0.0, "manual_valve_v")
        self.assertEqual(u32_value(h[6:8]), 0, "heartbeat")
        self.assertEqual(h[8], 0, "reset reads 0")
        self.assertEqual(h[9:13], [0, 0, 0, 0], "unlock reads 0 (never the key)")
        self.assertEqual(f32_value(h[13:15], "ABCD"), 0.0, "record_s reads 0")
        t = self.regs(3, 20, 10, "holding 20-29")
        for name, i, expected in [("m_r", 0, 1.7627), ("m_l", 2, 1.0707), ("b_r", 4, 1.232), ("b_l", 6, -1.722),
                                  ("lc_mm", 8, 5.0)]:
            self.assertAlmostEqual(f32_value(t[i:i + 2], "ABCD"), expected, places=5, msg=name)
        # Input registers, every block whole.
        blocks = {a: self.regs(4, a, n, f"input {a}-{a + n - 1}") for a, n in self.INPUT_BLOCKS}
        b0 = blocks[0]
        position, error, valve, _, sensor = (f32_value(b0[i:i + 2], "ABCD") for i in range(0, 10, 2))
        self.assertLessEqual(abs(position), 0.5, "position_mm at start")
        self.assertAlmostEqual(position, sensor * MM_PER_VOLT, places=3, msg="position = sensor_v x 50 mm/V")
        self.assertAlmostEqual(error, 0.0 - position, places=4, msg="error_mm = setpoint - position")
        self.assertEqual(valve, 0.0, "valve_v in STOP: the safe command")
        self.assertEqual(b0[10], 0, "fault_code")
        self.assertEqual(tuple(blocks[12]), VERSION, "version_major/minor/patch")
        self.assertAlmostEqual(f32_value(blocks[16], "ABCD"), 0.005, places=7, msg="Ts_s")
        coefficients = blocks[20]
        self.assertAlmostEqual(f32_value(coefficients[0:2], "ABCD"), 1.0, places=6, msg="F0 (monic F)")
        self.assertTrue(all(math.isfinite(f32_value(coefficients[i:i + 2], "ABCD")) for i in range(0, 42, 2)),
                        "F, G, H coefficients are finite")
        self.assertEqual(u32_value(blocks[70][0:2]), 0, "move_number before any move")
        # The loop refreshes its statistics every 200 cycles (1 s): right after start they may be 0.
        cycles = self.wait_until(lambda: (lambda n: (n > 0, n))(u32_value(self.regs(4, 102, 2))), 3.0, "cycles > 0")
        self.assertGreater(cycles, 0, "cycles")
        loop = self.regs(4, 90, 14, "input 90-103")
        s = blocks[110]
        uptime = f32_value(s[0:2], "ABCD")
        self.assertTrue(0.0 < uptime < 60.0, f"uptime_s {uptime}")
        self.assertEqual(u32_value(s[4:6]), 0, "faults since start")
        self.assertEqual(u32_value(s[6:8]), 0, "io_errors")
        self.assertGreater(u32_value(s[14:16]), 0, "modbus_requests")
        self.assertGreaterEqual(s[16], 1, "modbus_clients")
        # The loop runs: cycles and uptime advance.
        time.sleep(0.1)  # stays, the stimulus: 0.1 s of loop cycles
        later = self.regs(4, 90, 14, "input 90-103")
        self.assertGreater(u32_value(later[12:14]), u32_value(loop[12:14]), "cycles advance")

    def test_2_exceptions(self):
        c = self.c
        self.refused(c.read_holding_registers(15, 1, slave=UNIT), ILLEGAL_ADDRESS, "read unmapped holding 15")
        self.refused(c.read_input_registers(199, 1, slave=UNIT), ILLEGAL_ADDRESS, "read unmapped input 199")
        self.refused(c.read_input_registers(10, 3, slave=UNIT), ILLEGAL_ADDRESS, "read input 10-12 across the hole at 11")
        coils_end, inputs_end = self.bit_table_ends("coil")[1], self.bit_table_ends("discrete")[1]
        self.refused(c.read_coils(coils_end, 1, slave=UNIT), ILLEGAL_ADDRESS, f"read coil {coils_end}, past the padding")
        self.refused(c.read_discrete_inputs(inputs_end, 1, slave=UNIT), ILLEGAL_ADDRESS,
                     f"read discrete input {inputs_end}, past the padding")
        self.refused(c.read_discrete_inputs(inputs_end - 8, 16, slave=UNIT), ILLEGAL_ADDRESS,
                     f"read discrete inputs {inputs_end - 8}-{inputs_end + 7}, across the padding's end")
        self.refused(c.write_register(15, 1, slave=UNIT), ILLEGAL_ADDRESS, "write unmapped holding 15")
        self.refused(c.write_coil(1, True, slave=UNIT), ILLEGAL_ADDRESS, "write unmapped coil 1")
        self.refused(c.write_register(0, 0x42F0, slave=UNIT), ILLEGAL_VALUE, "FC6 on holding 0: half of setpoint_mm")
        self.refused(c.write_register(1, 0, slave=UNIT), ILLEGAL_VALUE, "FC6 on holding 1: the low half of setpoint_mm")
        self.refused(c.write_registers(0, f32_words(600.0, "ABCD"), slave=UNIT), ILLEGAL_VALUE, "setpoint 600 (max 500)")
        self.refused(c.write_registers(0, f32_words(-1.0, "ABCD"), slave=UNIT), ILLEGAL_VALUE, "setpoint -1 (min 0)")
        self.refused(c.write_register(2, 3, slave=UNIT), ILLEGAL_VALUE, "mode 3 (fault is read-only)")
        self.refused(c.write_coil(0, False, slave=UNIT), ILLEGAL_VALUE, "coil reset written 0 (range 1..1)")
        self.refused(c.write_registers(4, f32_words(1.0, "ABCD"), slave=UNIT), CANNOT_APPLY, "manual_valve_v in STOP")
        self.refused(c.write_registers(28, f32_words(7.5, "ABCD"), slave=UNIT), CANNOT_APPLY, "lc_mm while locked")
        self.refused(c.write_register(9, 1234, slave=UNIT), ILLEGAL_VALUE, "unlock with a wrong key")
        self.refused(c.read_holding_registers(0, 2, slave=7), OTHER_UNIT, "read for unit 7")
        self.refused(c.write_register(2, 1, slave=7), OTHER_UNIT, "write for unit 7")
        self.refused(self.device_information(BASIC, unit=7), OTHER_UNIT, "FC43 for unit 7")
        self.refused(self.device_information(SPECIFIC, 0x07), ILLEGAL_ADDRESS, "FC43 read code 04, object 7 (none)")
        self.refused(self.device_information(0x05), ILLEGAL_VALUE, "FC43 read code 05")
        # Nothing refused took effect.
        h = self.regs(3, 0, 4)
        self.assertEqual((f32_value(h[0:2], "ABCD"), h[2]), (0.0, 0), "setpoint and mode unchanged")
        self.assertAlmostEqual(f32_value(self.regs(3, 28, 2), "ABCD"), 5.0, places=6, msg="lc_mm unchanged")
        self.assertEqual(self.ok(c.read_discrete_inputs(3, 1, slave=UNIT), "locked").bits[0], True, "still locked")

    def test_3_unlock_and_tune(self):
        c = self.c
        self.ok(unlock(c), "unlock with the key")
        self.assertEqual(self.ok(c.read_discrete_inputs(3, 1, slave=UNIT), "locked").bits[0], False,
                         "locked discrete input after the key")
        self.assertEqual(self.regs(3, UNLOCK_ADDRESS, 4), [0, 0, 0, 0], "unlock reads 0, not the key")
        self.ok(c.write_registers(28, f32_words(7.5, "ABCD"), slave=UNIT), "lc_mm 7.5 while unlocked")
        self.wait_until(lambda: (f32_value(self.regs(3, 28, 2), "ABCD") == 7.5, f32_value(self.regs(3, 28, 2), "ABCD")),
                        2.0, "lc_mm reads back 7.5", every_s=0.02)
        self.refused(c.write_registers(28, f32_words(150.0, "ABCD"), slave=UNIT), ILLEGAL_VALUE, "lc_mm 150 (max 100)")
        self.ok(c.write_registers(28, f32_words(5.0, "ABCD"), slave=UNIT), "lc_mm back to 5")
        self.wait_until(lambda: (f32_value(self.regs(3, 28, 2), "ABCD") == 5.0, None), 2.0, "lc_mm reads back 5",
                        every_s=0.02)

    def test_4_setpoint_mode_move_and_fc23(self):
        c = self.c
        try:
            # RUN first (it holds the piston where it is), then the setpoint moves it.
            self.beat()
            self.ok(c.write_register(2, 1, slave=UNIT), "FC6 mode 1 (run)")
            self.wait_until(lambda: (self.mode() == 1, self.mode()), 2.0, "mode reads 1 (run)", every_s=0.02)
            self.ok(c.write_registers(0, f32_words(120.0, "ABCD"), slave=UNIT), "FC16 setpoint 120 (ABCD)")
            self.assertEqual(f32_value(self.regs(3, 0, 2), "ABCD"), 120.0, "setpoint reads back 120")
            # docs/registers.md's hint for pymodbus' own decoder, as written there.
            from pymodbus.constants import Endian
            from pymodbus.payload import BinaryPayloadDecoder
            decoder = BinaryPayloadDecoder.fromRegisters(self.regs(3, 0, 2), byteorder=Endian.Big, wordorder=Endian.Big)
            self.assertEqual(decoder.decode_32bit_float(), 120.0, "the documented BinaryPayloadDecoder arguments decode it")
            start = time.monotonic()
            moving = self.position()
            self.move_to(120.0)
            print(f"\n  epa.csv: 0 -> 120 mm within 3 mm after {time.monotonic() - start:.2f} s "
                  f"(first poll {moving:.2f} mm)", file=sys.stderr)
            # One snapshot, read in one request: the ABCD floats agree with each other.
            b = self.regs(4, 0, 10)
            position, error, _, _, sensor = (f32_value(b[i:i + 2], "ABCD") for i in range(0, 10, 2))
            self.assertAlmostEqual(position, sensor * MM_PER_VOLT, places=2, msg="position = sensor_v x 50 mm/V")
            self.assertAlmostEqual(error, 120.0 - position, places=3, msg="error_mm = setpoint - position")
            # FC23: write the setpoint 200 and read setpoint and mode back in one transaction. (An upward
            # step: FF-IDZ may stop up to ~l_c short on the paper's model, and more so moving down.)
            rr = self.ok(c.readwrite_registers(read_address=0, read_count=4, write_address=0,
                                               write_registers=f32_words(200.0, "ABCD"), unit=UNIT), "FC23 setpoint 200")
            self.assertEqual(len(rr.registers), 4, "FC23 read count")
            self.assertEqual(f32_value(rr.registers[0:2], "ABCD"), 200.0, "FC23 answer: setpoint (written before the read)")
            self.assertEqual(rr.registers[2:4], [1, 3], "FC23 answer: mode run, controller pp-traj")
            self.move_to(200.0)
            self.assertEqual(f32_value(self.regs(3, 0, 2), "ABCD"), 200.0, "setpoint reads back 200 after FC23")
            self.assertEqual(self.mode(), 1, "still in RUN (no fault)")
            moves = self.regs(4, 70, 6)
            self.assertGreaterEqual(u32_value(moves[0:2]), 1, "move_number counts the moves")
        finally:
            self.to_stop()

    def test_5_fault_and_coil_reset(self):
        c = self.c
        self.beat()
        self.ok(c.write_register(2, 1, slave=UNIT), "mode 1 (run)")
        # The heartbeat stops changing: heartbeat-lost (7) after heartbeat_timeout_s.
        self.wait_until(lambda: (self.mode() == 3, self.mode()), HEARTBEAT_TIMEOUT_S + 3.0, "mode reads 3 (fault)",
                        every_s=0.1)
        self.assertEqual(self.regs(4, 10, 1)[0], 7, "fault_code: heartbeat lost")
        self.assertEqual(self.ok(c.read_discrete_inputs(0, 1, slave=UNIT), "fault_active").bits[0], True, "fault_active")
        self.refused(c.write_register(2, 1, slave=UNIT), CANNOT_APPLY, "mode 1 while the fault is latched")
        rr = self.ok(c.write_coil(0, True, slave=UNIT), "FC5 coil reset")
        self.assertEqual(rr.value, True, "FC5 echo")
        self.wait_until(lambda: (self.mode() == 0, self.mode()), 2.0, "mode 0 (stop) after the coil reset", every_s=0.02)
        self.assertEqual(self.regs(4, 10, 1)[0], 0, "fault_code cleared")
        self.assertEqual(self.ok(c.read_discrete_inputs(0, 4, slave=UNIT), "discrete").bits[:4], [False, False, True, False],
                         "fault_active 0, io_ok 1, still unlocked")
        s = self.regs(4, 114, 2)
        self.assertEqual(u32_value(s), 1, "faults since start")
        # FC15 on the same coil works too (nothing latched: no effect, but accepted).
        self.ok(c.write_coils(0, [True], slave=UNIT), "FC15 coil reset")


    def test_6_device_identification(self):
        version = ".".join(str(v) for v in VERSION).encode()
        basic = self.ok(self.device_information(BASIC), "FC43/14 read code 01 (basic)")
        print(f"\n  FC43 basic: read code {basic.read_code:#04x}, conformity {basic.conformity:#04x}, "
              f"more follows {basic.more_follows:#04x}, objects {basic.information}", file=sys.stderr)
        self.assertEqual(basic.information, {0x00: b"EPA project", 0x01: b"epa", 0x02: version},
                         "VendorName, ProductCode, MajorMinorRevision = epa --version's")
        self.assertEqual((basic.read_code, basic.conformity, basic.more_follows, basic.next_object_id), (BASIC, 0x82, 0, 0))
        regular = self.ok(self.device_information(REGULAR), "FC43/14 read code 02 (regular)")
        print(f"  FC43 regular: conformity {regular.conformity:#04x}, objects {regular.information}", file=sys.stderr)
        self.assertEqual(regular.information, {
            0x00: b"EPA project", 0x01: b"epa", 0x02: version,
            0x03: f"http://127.0.0.1:{self.app.web_port}/".encode(),  # the status page, at the address it was reached by
            0x04: b"EPA electro-pneumatic axis controller", 0x05: b"epa appliance", 0x06: b"epa.csv"})
        self.assertEqual((regular.conformity, regular.more_follows, regular.number_of_objects), (0x82, 0, 7))
        extended = self.ok(self.device_information(EXTENDED), "FC43/14 read code 03: answered at the regular level")
        self.assertEqual(extended.information, regular.information, "no extended objects")
        one = self.ok(self.device_information(SPECIFIC, 0x02), "FC43/14 read code 04, object 2")
        self.assertEqual((one.information, one.number_of_objects, one.more_follows), ({0x02: version}, 1, 0))
        self.ok(self.device_information(BASIC, unit=0), "FC43/14 for unit 0")

    def test_7_unit_id_0_and_bit_blocks(self):
        c = self.c
        # Unit id 0 (and 0xFF) is this device on TCP: reads and writes answered as for unit 1.
        self.assertEqual(tuple(self.ok(c.read_input_registers(12, 3, slave=0), "FC4 for unit 0").registers), VERSION,
                         "version_major/minor/patch read for unit 0")
        self.assertEqual(tuple(self.ok(c.read_input_registers(12, 3, slave=0xFF), "FC4 for unit 0xFF").registers), VERSION)
        self.ok(c.write_register(2, 0, slave=0), "FC6 mode 0 (stop) for unit 0")
        # Bit tables read in blocks of 8 and 16: what lies past the map's bits reads 0 (reserved).
        inputs_end, inputs_padded = self.bit_table_ends("discrete")
        inputs = self.ok(c.read_discrete_inputs(0, 16, slave=UNIT), "16 discrete inputs from 0").bits
        self.assertEqual(len(inputs), 16)
        self.assertEqual(inputs[:3], [False, False, True], "fault_active, saturated, io_ok in STOP")
        self.assertEqual(inputs[inputs_end:16], [False] * (16 - min(inputs_end, 16)), f"reserved from {inputs_end}")
        self.assertEqual(self.ok(c.read_discrete_inputs(0, 8, slave=UNIT), "8 discrete inputs").bits[:3], inputs[:3])
        last = self.ok(c.read_discrete_inputs(inputs_padded - 16, 16, slave=UNIT),
                       f"discrete inputs {inputs_padded - 16}-{inputs_padded - 1}, the last block").bits
        self.assertEqual(len(last), 16)
        coils_end, coils_padded = self.bit_table_ends("coil")
        coils = self.ok(c.read_coils(0, 16, slave=UNIT), "16 coils from 0").bits
        self.assertEqual(coils[0], False, "reset reads 0")
        self.assertEqual(coils[coils_end:16], [False] * (16 - min(coils_end, 16)), f"reserved from {coils_end}")
        self.ok(c.read_coils(0, 8, slave=UNIT), "8 coils from 0")
        if coils_end < coils_padded:
            self.refused(c.write_coil(coils_padded - 1, True, slave=UNIT), ILLEGAL_ADDRESS,
                         f"write reserved coil {coils_padded - 1}: readable, never writable")


# ---- registers/examples/legacy-hmi.csv: CDAB floats against scaled int16 copies ----
class LegacyHmiMapTest(ApplianceTest):
    REGISTER_MAP = "registers/examples/legacy-hmi.csv"

    def snapshot_pair(self):
        """position (x10 int16 at input 1000, CDAB float at input 1010), read int, float, int again."""
        before = i16_value(self.regs(4, 1000, 1)[0]) / 10.0
        f = f32_value(self.regs(4, 1010, 2), "CDAB")
        after = i16_value(self.regs(4, 1000, 1)[0]) / 10.0
        return before, f, after

    def assert_same_position(self, what):
        # At rest the three reads agree; int16 rounds to 0.1 mm.
        before, f, after = self.snapshot_pair()
        lo, hi = min(before, after) - 0.05 - 1e-3, max(before, after) + 0.05 + 1e-3
        self.assertTrue(lo <= f <= hi, f"{what}: CDAB position {f} against int16 x10 {before}, {after}")
        return f

    def wait_position(self, target, tol=3.0, timeout_s=15.0):
        def check():
            p = f32_value(self.regs(4, 1010, 2), "CDAB")
            return abs(p - target) <= tol, p
        return self.wait_until(check, timeout_s, f"CDAB position within {tol} mm of {target} (3 polls in a row)",
                               every_s=0.2, times=3)

    def wait_settled(self, timeout_s=5.0):
        """Until two int16 position reads 0.3 s apart agree (the piston stands)."""
        last = [None]

        def check():
            p = self.regs(4, 1000, 1)[0]
            done, last[0] = p == last[0], p
            return done, p
        self.wait_until(check, timeout_s, "position settles", every_s=0.3)

    def test_1_read_every_table(self):
        c = self.c
        h = self.regs(3, 1000, 4, "holding 1000-1003")
        self.assertEqual(h, [0, 0, 0, 0], "setpoint x10, mode, reset, heartbeat at start")
        self.assertEqual(f32_value(self.regs(3, 1010, 2), "CDAB"), 0.0, "setpoint CDAB at start")
        i = self.regs(4, 1000, 4, "input 1000-1003")
        self.assertLessEqual(abs(i16_value(i[0])), 5, "position x10 at start")
        self.assertEqual(i16_value(i[2]), 0, "valve mV in STOP")
        self.assertEqual(i[3], 0, "fault_code")
        self.assertLessEqual(abs(f32_value(self.regs(4, 1010, 2), "CDAB")), 0.5, "position CDAB at start")
        self.assert_same_position("at start")
        # This map has no coils or discrete inputs and nothing at epa.csv's addresses.
        self.refused(c.read_coils(0, 1, slave=UNIT), ILLEGAL_ADDRESS, "read coil 0 (no coils in this map)")
        self.refused(c.read_discrete_inputs(0, 1, slave=UNIT), ILLEGAL_ADDRESS, "read discrete input 0 (none here)")
        self.refused(c.read_holding_registers(0, 2, slave=UNIT), ILLEGAL_ADDRESS, "read holding 0 (epa.csv's setpoint)")
        self.refused(c.read_input_registers(1004, 1, slave=UNIT), ILLEGAL_ADDRESS, "read unmapped input 1004")
        self.refused(c.read_input_registers(1000, 12, slave=UNIT), ILLEGAL_ADDRESS, "read input 1000-1011 across the hole")
        # Device identification names this map as the user application.
        app = self.ok(c.execute(ReadDeviceInformationRequest(read_code=0x04, object_id=0x06, unit=UNIT)), "FC43 object 6")
        self.assertEqual(app.information, {0x06: b"legacy-hmi.csv"}, "UserApplicationName: the map's file name")
        url = self.ok(c.execute(ReadDeviceInformationRequest(read_code=0x04, object_id=0x03, unit=UNIT)), "FC43 object 3")
        self.assertEqual(url.information, {0x03: b""}, "VendorUrl: empty, this appliance runs no status page")

    def test_2_exceptions(self):
        c = self.c
        self.refused(c.write_register(1000, 6000, slave=UNIT), ILLEGAL_VALUE, "setpoint int16 6000 (600 mm, max 500)")
        self.refused(c.write_registers(1010, f32_words(600.0, "CDAB"), slave=UNIT), ILLEGAL_VALUE, "setpoint CDAB 600")
        self.refused(c.write_register(1010, 0, slave=UNIT), ILLEGAL_VALUE, "FC6 on holding 1010: half of the CDAB setpoint")
        self.refused(c.write_register(1004, 1, slave=UNIT), ILLEGAL_ADDRESS, "write unmapped holding 1004")
        self.refused(c.read_input_registers(1000, 1, slave=7), OTHER_UNIT, "read for unit 7")
        self.assertEqual(self.regs(3, 1000, 2), [0, 0], "setpoint and mode unchanged")

    def test_3_float_word_orders(self):
        c = self.c
        try:
            # Setpoint written as a CDAB float: the int16 copy reads x10, the float reads back the same.
            self.ok(c.write_register(1001, 1, slave=UNIT), "mode 1 (run): holds the piston")
            self.ok(c.write_registers(1010, f32_words(80.0, "CDAB"), slave=UNIT), "FC16 setpoint 80 (CDAB): moves it")
            self.wait_until(lambda: (self.regs(3, 1000, 2) == [800, 1], self.regs(3, 1000, 2)), 2.0,
                            "holding 1000-1001 read setpoint x10 = 800, mode 1", every_s=0.02)
            words = self.regs(3, 1010, 2)
            self.assertEqual(f32_value(words, "CDAB"), 80.0, "setpoint CDAB reads back 80")
            self.assertEqual(words, f32_words(80.0, "CDAB"), "the words are low word first")
            self.assertNotEqual(f32_value(words, "ABCD"), 80.0, "decoded as ABCD it is not 80: the words are swapped")
            self.wait_position(80.0)
            self.wait_settled()
            p = self.assert_same_position("at 80 mm")
            self.assertLessEqual(abs(p - 80.0), 3.0)
            # Setpoint written as a scaled int16 (150.5 mm): the CDAB copy reads the same value.
            self.ok(c.write_register(1000, 1505, slave=UNIT), "FC6 setpoint 1505 (150.5 mm)")
            self.wait_until(lambda: (f32_value(self.regs(3, 1010, 2), "CDAB") == 150.5, self.regs(3, 1010, 2)), 2.0,
                            "setpoint CDAB reads 150.5", every_s=0.02)
            self.wait_position(150.5)
            self.wait_settled()
            p = self.assert_same_position("at 150.5 mm")
            self.assertLessEqual(abs(p - 150.5), 3.0)
            # error_mm (x10 at 1001) agrees with setpoint - position.
            e = i16_value(self.regs(4, 1001, 1)[0]) / 10.0
            self.assertAlmostEqual(e, 150.5 - p, delta=0.15, msg="error_mm x10")
            self.assertEqual(self.regs(4, 1003, 1)[0], 0, "no fault")
        finally:
            self.ok(c.write_register(1001, 0, slave=UNIT), "mode 0 (stop)")


def epa_version(epa):
    """The version `epa --version` prints ("epa 0.3.0") as a tuple of three numbers."""
    out = subprocess.run([epa, "--version"], capture_output=True, text=True, timeout=10).stdout.strip()
    match = re.fullmatch(r"epa (\d+)\.(\d+)\.(\d+)", out)
    if not match:
        sys.exit(f"FAIL: `{epa} --version` printed {out!r}, expected 'epa MAJOR.MINOR.PATCH'")
    return tuple(int(g) for g in match.groups())


def main():
    global EPA, SRC, VERSION
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    EPA, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if not os.access(EPA, os.X_OK):
        sys.exit(f"FAIL: {EPA} is not an executable")
    VERSION = epa_version(EPA)
    print(f"pymodbus {pymodbus.__version__} ({os.path.dirname(pymodbus.__file__)}), python {sys.version.split()[0]}",
          file=sys.stderr)
    suite = unittest.TestSuite()
    loader = unittest.TestLoader()
    for case in (EpaMapTest, LegacyHmiMapTest):
        suite.addTests(loader.loadTestsFromTestCase(case))
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    sys.exit(0 if result.wasSuccessful() else 1)


if __name__ == "__main__":
    main()
