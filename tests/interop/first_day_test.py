#!/usr/bin/env python3
"""First-day acceptance test of the epa positioning appliance, as an SCADA/HMI integrator sees it.

Usage: first_day_test.py <epa binary> <source dir>

Written from the documentation only (README.md, docs/registers.md, registers/epa.csv,
config/epa.toml, the run-file format), never from the implementation, so that its verdict does not
depend on it. It starts its own appliances (`epa serve`, simulated plant, loopback only),
talks Modbus TCP with Debian's python3-pymodbus 3.0 and HTTP with the standard library, and checks:

  A  the status word is true from the write on (setpoint writes, record starts, a halt short of
     its target, target_reached in STOP);
  B  no nuisance following error over moves of every law and speed, while a crippled axis still
     faults;
  C  one record of a move: the move registers, GET /api/moves, the move's run file, our own
     recomputation of its metrics from the file's samples and `epa tuning runs` all agree;
  D  laws change only when asked (a record's law runs that move only; the audit log has every
     change of holding 3).

Exit 0 when every check passes, 1 otherwise; the last line is `N passed, M failed`.
Each check prints PASS/FAIL with its figures. The checks run on separate appliances, in parallel
threads (PARALLEL), so the whole run stays within a few minutes on a 2-core machine.
"""

import os
import sys

# Debian's python3-pymodbus lives in /usr/bin/python3's site-packages; a python3 found first on the
# PATH (pyenv, venv) may not see it: run again under Debian's interpreter then.
try:
    import pymodbus  # noqa: F401
except ImportError:
    if (os.path.exists("/usr/bin/python3") and not os.environ.get("FIRST_DAY_TEST_REEXEC")
            and os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3")):
        os.environ["FIRST_DAY_TEST_REEXEC"] = "1"
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    print("first_day_test: pymodbus is not importable (apt-get install python3-pymodbus)")
    print("0 passed, 1 failed")
    sys.exit(1)

import atexit
import decimal
import glob
import json
import logging
import math
import random
import re
import secrets
import shutil
import signal
import socket
import struct
import subprocess
import tempfile
import threading
import time
import traceback
import urllib.request

from pymodbus.client import ModbusTcpClient

logging.getLogger("pymodbus").setLevel(logging.CRITICAL)

# ---------------------------------------------------------------------------------------------
# Counts and bounds (the budget: the whole script in under ~4 minutes on 2 cores)
# ---------------------------------------------------------------------------------------------
SEED = 20261206
PARALLEL = True                 # each check group on its own appliance, in its own thread

A_SETPOINT_MOVES = 200          # setpoint writes, each read back at once
A_RECORD_STARTS = 20            # record starts, each read back at once
A_MOVE_MIN_MM, A_MOVE_MAX_MM = 25.0, 110.0
B_MOVES_PER_LAW = 25            # x 4 laws = 100 moves
B_POLL_S = 0.02
B_MOVE_BOUND_S = 8.0
C_MIN_MOVES = 50                # moves verified (record of a move)
C_TIME_BUDGET_S = 200.0         # no new move is started in C after this
C_LO_MM, C_HI_MM = 150.0, 350.0  # C's setpoint targets: FF-IDZ's swings reach the end stops from 70 mm
C_HEARTBEAT_TIMEOUT_S = 1.5
C_HEARTBEAT_PERIOD_S = 0.2

WINDOW_MM = 1.0                 # [motion] in_position_window_mm (default)
IN_POSITION_TIME_S = 0.1        # [motion] in_position_time_s (default)
IN_POSITION_BOUND_S = 10.0
MOVE_END_BOUND_S = 8.0          # a move ends within move_window_s (5 s) + slack
SLOW_END_BOUND_S = 16.0
BINARY_WAIT_S = 30.0            # the binary may be being rebuilt
START_BOUND_S = 20.0
STOP_GRACE_S = 5.0
GROUP_JOIN_BOUND_S = 480.0

TOL_MM, TOL_S, TOL_PCT = 0.01, 0.005, 0.01

# Under the sanitizers (EPA_SANITIZER_RUN=1, the asan preset) the same checks on fewer moves: what
# they add there is the instrumented appliance on these paths; the acceptance counts are the
# release run's.
if os.environ.get("EPA_SANITIZER_RUN") == "1":
    A_SETPOINT_MOVES, A_RECORD_STARTS, B_MOVES_PER_LAW, C_MIN_MOVES = 40, 8, 10, 20
    C_HEARTBEAT_TIMEOUT_S = 3.0  # the instrumented appliances and this script share two loaded cores

# ---------------------------------------------------------------------------------------------
# The register map (docs/registers.md)
# ---------------------------------------------------------------------------------------------
H_SETPOINT, H_MODE, H_CONTROLLER, H_HEARTBEAT, H_RESET, H_UNLOCK = 0, 2, 3, 6, 8, 9
H_CONTROL_WORD, H_RECORD_SELECT, H_RECORD_BASE = 50, 51, 1000
I_POSITION, I_FAULT_CODE, I_MOVE_BLOCK, I_STATUS = 0, 10, 70, 140
CW_START, CW_HALT = 0x1, 0x2
SW_READY, SW_RUN, SW_MOVING, SW_IN_POS, SW_REACHED = 0x1, 0x2, 0x4, 0x8, 0x10
SW_FOLLOWING, SW_WARNING, SW_FAULT, SW_ACK, SW_HALTED = 0x20, 0x40, 0x80, 0x100, 0x200
SW_OFF_TARGET = 0x1000
MODE_STOP, MODE_RUN = 0, 1
LAWS = {0: "pp", 1: "pp-ngidz", 2: "pp-ffidz", 3: "pp-traj"}
LAW_CODES = {v: k for k, v in LAWS.items()}
RECORD_RUNNING_LAW = 255
FAULT_FOLLOWING_ERROR, FAULT_HEARTBEAT_LOST = 6, 7
# move_end (input 141, docs/registers.md): 0 in position, 1 cut short by a new target, 2 halted,
# 3 stopped (mode change), 4 fault, 5 controller switched, 6 timeout, 7 off target; the run file's
# move_end names them as below.
MOVE_END_NAMES = {0: "in_position", 1: "cut_short", 2: "halted", 3: "stopped", 4: "fault",
                  5: "controller_switched", 6: "timeout", 7: "off_target"}
NAN = float("nan")


def sw_text(s):
    names = [(SW_READY, "ready"), (SW_RUN, "run"), (SW_MOVING, "moving"), (SW_IN_POS, "in_pos"),
             (SW_REACHED, "reached"), (SW_FOLLOWING, "FE"), (SW_WARNING, "warn"),
             (SW_FAULT, "FAULT"), (SW_ACK, "ack"), (SW_HALTED, "halted"), (0x400, "jog"),
             (0x800, "manual"), (SW_OFF_TARGET, "off_target")]
    return "0x%04x[%s]" % (s, ",".join(n for m, n in names if s & m))


def f2w(x):
    return list(struct.unpack(">HH", struct.pack(">f", float(x))))


def w2f(hi, lo):
    return struct.unpack(">f", struct.pack(">HH", hi, lo))[0]


def isnan(x):
    return x is None or (isinstance(x, float) and math.isnan(x))


def fmt(x, nd=4):
    if x is None:
        return "None"
    if isinstance(x, float):
        return "NaN" if math.isnan(x) else ("%.*f" % (nd, x))
    return str(x)


def close(a, b, tol):
    if isnan(a) or isnan(b):
        return isnan(a) and isnan(b)
    return abs(a - b) <= tol + 1e-9


# ---------------------------------------------------------------------------------------------
# Reporting
# ---------------------------------------------------------------------------------------------
_print_lock = threading.Lock()


def progress(msg):
    with _print_lock:
        print("  ... " + msg, file=sys.stderr, flush=True)


class Check:
    MAX_FAIL_LINES = 30

    def __init__(self, cid, title):
        self.cid, self.title = cid, title
        self.lines, self.failures = [], []
        self.done = False

    def info(self, msg):
        self.lines.append(msg)

    def fail(self, msg):
        self.failures.append(msg)

    @property
    def passed(self):
        return self.done and not self.failures

    def render(self):
        out = ["[%s] %s: %s" % (self.cid, "PASS" if self.passed else "FAIL", self.title)]
        out += ["    " + l for l in self.lines]
        if not self.done:
            out.append("    not completed")
        for f in self.failures[:self.MAX_FAIL_LINES]:
            out.append("    FAIL: " + f)
        if len(self.failures) > self.MAX_FAIL_LINES:
            out.append("    ... and %d more failures" % (len(self.failures) - self.MAX_FAIL_LINES))
        return "\n".join(out)


# ---------------------------------------------------------------------------------------------
# The appliance under test
# ---------------------------------------------------------------------------------------------
_procs = []
_procs_lock = threading.Lock()


def _cleanup_procs():
    with _procs_lock:
        procs = list(_procs)
    for p in procs:
        _stop_proc(p)


def _stop_proc(p):
    if p.poll() is not None:
        return
    try:
        p.terminate()
        p.wait(STOP_GRACE_S)
    except subprocess.TimeoutExpired:
        p.kill()
        try:
            p.wait(5)
        except subprocess.TimeoutExpired:
            pass
    except OSError:
        pass


atexit.register(_cleanup_procs)


def _on_signal(signum, _frame):
    _cleanup_procs()
    sys.exit(128 + signum)


def free_ports(n):
    socks, ports = [], []
    for _ in range(n):
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.bind(("127.0.0.1", 0))
        socks.append(s)
        ports.append(s.getsockname()[1])
    for s in socks:
        s.close()
    return ports


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(v)


def make_unlock_key():
    # 16 hex digits that are not "trivial" (README: at least 6 different digits, no runs, no patterns)
    for _ in range(1000):
        k = secrets.token_hex(8)
        d = [int(c, 16) for c in k]
        runs = any(d[i + 1] - d[i] == d[i + 2] - d[i + 1] and abs(d[i + 1] - d[i]) <= 1
                   for i in range(len(d) - 2))
        if len(set(k)) >= 10 and not runs:
            return k
    return "8f3a1c9e5b7d2046"


class Appliance:
    def __init__(self, env, name, limits=None, hal_sim=None, unlock=True):
        self.env, self.name = env, name
        self.dir = os.path.join(env.tmp, name)
        os.makedirs(self.dir)
        self.mb_port, self.web_port = env.take_ports(2)
        self.token = secrets.token_hex(20)
        self.unlock_key = make_unlock_key() if unlock else ""
        self.db = os.path.join(self.dir, "epa.db")
        self.runs = os.path.join(self.dir, "runs")
        self.log_path = os.path.join(self.dir, "epa.log")
        sections = {
            "loop": {"realtime_priority": 0, "lock_memory": False, "cpu_dma_latency_us": -1},
            "limits": dict(limits or {}),
            "store": {"path": self.db},
            "recorder": {"directory": self.runs},
            "modbus": {"address": "127.0.0.1", "port": self.mb_port,
                       "register_map": os.path.abspath(os.path.join(env.src, "registers", "epa.csv")),
                       "unlock_key": self.unlock_key, "unlock_timeout_s": 900.0},
            "web": {"address": "127.0.0.1", "port": self.web_port, "token": self.token,
                    "static_dir": os.path.abspath(os.path.join(env.src, "web"))},
            "hal.sim": dict(hal_sim or {}),
        }
        text = "# written by tests/interop/first_day_test.py\n"
        for sec, kv in sections.items():
            if not kv:
                continue
            text += "\n[%s]\n" % sec
            for k, v in kv.items():
                text += "%s = %s\n" % (k, toml_value(v))
        self.config = os.path.join(self.dir, "epa.toml")
        with open(self.config, "w") as f:
            f.write(text)
        self.proc = None

    def start(self):
        logf = open(self.log_path, "wb")
        self.proc = subprocess.Popen([self.env.binary, "serve", "--config", self.config],
                                     cwd=self.dir, stdout=logf, stderr=subprocess.STDOUT,
                                     stdin=subprocess.DEVNULL)
        logf.close()
        with _procs_lock:
            _procs.append(self.proc)
        deadline = time.monotonic() + START_BOUND_S
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError("appliance %s exited with %s at start: %s"
                                   % (self.name, self.proc.returncode, self.log_tail()))
            if self._answers(self.mb_port) and self._answers(self.web_port):
                return self
            time.sleep(0.1)
        raise RuntimeError("appliance %s: ports %d/%d did not answer within %.0f s: %s"
                           % (self.name, self.mb_port, self.web_port, START_BOUND_S, self.log_tail()))

    @staticmethod
    def _answers(port):
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=0.5):
                return True
        except OSError:
            return False

    def stop(self):
        if self.proc is not None:
            _stop_proc(self.proc)

    def log_tail(self, n=8):
        try:
            with open(self.log_path, "rb") as f:
                lines = f.read().decode("utf-8", "replace").splitlines()
            return " | ".join(lines[-n:])
        except OSError:
            return "(no log)"

    def http_json(self, path, timeout=5.0):
        url = "http://127.0.0.1:%d%s" % (self.web_port, path)
        with urllib.request.urlopen(url, timeout=timeout) as r:
            return json.loads(r.read().decode("utf-8"))

    def run_files(self, number):
        return sorted(glob.glob(os.path.join(self.runs, "move-%04d-*" % number)))


class ModbusError(RuntimeError):
    pass


class Mb:
    """A Modbus TCP connection (unit 1) with the few typed accesses the checks need."""

    def __init__(self, port):
        self.c = ModbusTcpClient("127.0.0.1", port=port, timeout=3, retries=1)
        if not self.c.connect():
            raise ModbusError("cannot connect to 127.0.0.1:%d" % port)

    def close(self):
        try:
            self.c.close()
        except Exception:
            pass

    @staticmethod
    def _ok(r, what):
        if r is None or not hasattr(r, "isError") or r.isError():
            raise ModbusError("%s: %s" % (what, r))
        return r

    def ir(self, addr, n):
        return self._ok(self.c.read_input_registers(addr, n, slave=1), "read input %d+%d" % (addr, n)).registers

    def hr(self, addr, n):
        return self._ok(self.c.read_holding_registers(addr, n, slave=1), "read holding %d+%d" % (addr, n)).registers

    def w1(self, addr, v):
        return self._ok(self.c.write_register(addr, int(v), slave=1), "write holding %d := %s" % (addr, v))

    def wn(self, addr, values):
        return self._ok(self.c.write_registers(addr, [int(v) for v in values], slave=1),
                        "write holding %d := %s" % (addr, values))

    def try_wn(self, addr, values):
        r = self.c.write_registers(addr, [int(v) for v in values], slave=1)
        return r is not None and hasattr(r, "isError") and not r.isError(), r

    def f32(self, addr):
        r = self.ir(addr, 2)
        return w2f(r[0], r[1])

    def wf32(self, addr, x):
        return self.wn(addr, f2w(x))

    def status(self):
        return self.ir(I_STATUS, 1)[0]

    def pos(self):
        return self.f32(I_POSITION)

    def unlock(self, key_hex):
        k = int(key_hex, 16)
        self.wn(H_UNLOCK, [(k >> 48) & 0xFFFF, (k >> 32) & 0xFFFF, (k >> 16) & 0xFFFF, k & 0xFFFF])

    def move_regs(self):
        """move_number, from, to, rise, settling, ess, overshoot (70-83) and move_end (141)."""
        for _ in range(3):
            r = self.ir(I_MOVE_BLOCK, 14)
            end = self.ir(I_STATUS + 1, 1)[0]
            r2 = self.ir(I_MOVE_BLOCK, 2)
            if r2 == r[0:2]:
                break
        fl = [w2f(r[i], r[i + 1]) for i in range(2, 14, 2)]
        return {"number": (r[0] << 16) | r[1], "from_mm": fl[0], "to_mm": fl[1], "rise_s": fl[2],
                "settling_s": fl[3], "ess_mm": fl[4], "overshoot_pct": fl[5], "move_end_code": end}

    def move_number(self):
        r = self.ir(I_MOVE_BLOCK, 2)
        return (r[0] << 16) | r[1]

    def write_record(self, n, target, speed, window, law, key=None):
        vals = f2w(target) + f2w(speed) + f2w(window) + [law]
        ok, r = self.try_wn(H_RECORD_BASE + 8 * (n - 1), vals)
        if not ok and key:
            self.unlock(key)
            ok, r = self.try_wn(H_RECORD_BASE + 8 * (n - 1), vals)
        if not ok:
            raise ModbusError("write record %d (target %.3f, speed %g, window %g, law %d): %s"
                              % (n, target, speed, window, law, r))

    def start_edge(self, bound_s=1.0, on_poll=None):
        """control word: start 1, wait for ack (bounded), start 0. Returns (acked, first status)."""
        self.w1(H_CONTROL_WORD, CW_START)
        first = self.status()
        acked = bool(first & SW_ACK)
        t0 = time.monotonic()
        s = first
        while not acked and time.monotonic() - t0 < bound_s:
            s = self.status()
            if on_poll:
                on_poll(s)
            acked = bool(s & SW_ACK)
            if not acked:
                time.sleep(0.005)
        self.w1(H_CONTROL_WORD, 0)
        return acked, first

    def halt_edge(self):
        self.w1(H_CONTROL_WORD, CW_HALT)
        time.sleep(0.03)  # stays, the stimulus: the width of the halt pulse
        self.w1(H_CONTROL_WORD, 0)

    def wait_in_position(self, target, window, bound_s=IN_POSITION_BOUND_S):
        """Until in_position with the piston within the window of target (bounded)."""
        t0 = time.monotonic()
        s, p = 0, NAN
        while time.monotonic() - t0 < bound_s:
            s = self.status()
            if s & SW_FAULT:
                return False, time.monotonic() - t0, s, self.pos()
            if s & SW_IN_POS:
                p = self.pos()
                if target is None or abs(p - target) <= window:
                    return True, time.monotonic() - t0, s, p
            time.sleep(0.01)
        return False, time.monotonic() - t0, s, self.pos()

    def wait_move_number(self, n, bound_s):
        t0 = time.monotonic()
        m = self.move_number()
        while m < n and time.monotonic() - t0 < bound_s:
            time.sleep(0.01)
            m = self.move_number()
        return m

    def recover_fault(self):
        """Reset a latched fault and enable again."""
        self.w1(H_RESET, 1)
        t0 = time.monotonic()
        while self.status() & SW_FAULT and time.monotonic() - t0 < 3.0:
            time.sleep(0.02)
        self.w1(H_MODE, MODE_RUN)
        time.sleep(0.2)


def pick_target(rng, pos, dmin, dmax, lo, hi):
    """A target dmin..dmax from pos, inside [lo, hi]."""
    for _ in range(200):
        d = rng.uniform(dmin, dmax)
        t = pos + d if rng.random() < 0.5 else pos - d
        if lo <= t <= hi:
            return t
    # fall back: as far as possible the way there is room
    return hi if hi - pos > pos - lo else lo


# ---------------------------------------------------------------------------------------------
# Run files (epa-run/1) and the metrics' definitions
# ---------------------------------------------------------------------------------------------
def read_run_file(path):
    meta, header, rows = {}, None, []
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            if line.startswith("#"):
                body = line[1:].strip()
                if "=" in body:
                    k, v = body.split("=", 1)
                    meta[k.strip()] = v.strip()
                elif body:
                    meta.setdefault("_schema", body)
                continue
            if header is None:
                header = [h.strip() for h in line.split(",")]
                continue
            rows.append(line.split(","))
    if header is None or "y_mm" not in header:
        raise ValueError("no header with y_mm")
    iy = header.index("y_mm")
    y = []
    for r in rows:
        if len(r) != len(header):
            raise ValueError("row with %d fields, header %d" % (len(r), len(header)))
        y.append(float(r[iy]))
    return meta, y


def wait_run_file(app, number, bound_s=4.0):
    """The move's run file once written whole: (path, meta, y) or (None, None, error text)."""
    t0 = time.monotonic()
    err = "no file move-%04d-* in %s" % (number, app.runs)
    while time.monotonic() - t0 < bound_s:
        files = app.run_files(number)
        if files:
            path = files[0]
            try:
                s1 = os.path.getsize(path)
                time.sleep(0.1)
                if os.path.getsize(path) == s1:
                    meta, y = read_run_file(path)
                    if y:
                        return path, meta, y
                    err = "%s: no samples" % path
            except (OSError, ValueError) as e:
                err = "%s: %s" % (path, e)
        time.sleep(0.1)
    return None, None, err


def recompute(y, Ts, frm, tgt, move_end, ess_window_s):
    L = abs(tgt - frm)
    d = 1.0 if tgt >= frm else -1.0
    prog = [d * (v - frm) for v in y]
    i10 = next((k for k, p in enumerate(prog) if p >= 0.1 * L), None)
    i90 = next((k for k, p in enumerate(prog) if p >= 0.9 * L), None)
    rise = (i90 - i10) * Ts if (i90 is not None and i10 is not None) else NAN
    halted = move_end == "halted"
    ended = move_end in ("in_position", "timeout", "off_target")  # let to end (docs: a move's figures)
    passed = max(prog) > L
    overshoot = NAN if halted or not (ended or passed) else max(0.0, max(prog) - L) / L * 100.0
    outside = [k for k, v in enumerate(y) if abs(v - tgt) > 0.02 * L]
    if not ended:
        settling = NAN
    elif not outside:
        settling = 0.0
    elif outside[-1] == len(y) - 1:
        settling = NAN
    else:
        settling = (outside[-1] + 1) * Ts
    if not ended or isnan(ess_window_s):
        ess = NAN
    else:
        m = int(round(ess_window_s / Ts))
        tail = y[-m:] if 0 < m <= len(y) else y
        ess = sum(abs(tgt - v) for v in tail) / len(tail)
    return {"rise_s": rise, "settling_s": settling, "ess_mm": ess, "overshoot_pct": overshoot}


def meta_float(meta, key):
    try:
        return float(meta[key])
    except (KeyError, ValueError):
        return NAN


def api_float(entry, key):
    v = entry.get(key)
    if v is None:
        return NAN
    try:
        return float(v)
    except (TypeError, ValueError):
        return NAN


def law_name(v):
    """A law as the API or the audit log gives it: a code or a name."""
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return LAWS.get(int(v), str(v))
    if isinstance(v, str):
        s = v.strip().lower()
        if s in LAW_CODES:
            return s
        try:
            return LAWS.get(int(float(s)), s)
        except ValueError:
            return s
    return str(v)


# ---------------------------------------------------------------------------------------------
# A. Status word true from the write on
# ---------------------------------------------------------------------------------------------
def group_a(env):
    a1 = Check("A1", "status word after %d setpoint writes: no in_position/target_reached while "
                     "the piston is outside the window of the new target" % A_SETPOINT_MOVES)
    a2 = Check("A2", "status word after %d record starts (same rule)" % A_RECORD_STARTS)
    a3 = Check("A3", "halt short of a record's target: in_position 0, halted 1 once moving clears")
    a4 = Check("A4", "target_reached reads 0 in STOP")
    checks = [a1, a2, a3, a4]
    app = Appliance(env, "A")
    mb = None
    try:
        app.start()
        mb = Mb(app.mb_port)
        rng = random.Random(SEED + 1)
        mb.w1(H_CONTROL_WORD, 0)
        mb.w1(H_CONTROLLER, 3)       # pp-traj: it comes into position quickly and reliably
        mb.w1(H_MODE, MODE_RUN)
        ok, dt, s, p = mb.wait_in_position(None, WINDOW_MM, 5.0)
        a1.info("law pp-traj (holding 3 := 3), mode RUN; in position after enable: %s (%.2f s, %s, %.3f mm)"
                % (ok, dt, sw_text(s), p))

        # A1: setpoint writes
        viol, timeouts, t_wait = [], [], []
        n_inpos_seen = n_reached_seen = 0
        pos = mb.pos()
        t_start = time.monotonic()
        for i in range(A_SETPOINT_MOVES):
            t = pick_target(rng, pos, A_MOVE_MIN_MM, A_MOVE_MAX_MM, 50.0, 450.0)
            mb.wf32(H_SETPOINT, t)
            s = mb.status()          # the next request on the same connection
            p = mb.pos()             # and the one after it
            if s & SW_IN_POS:
                n_inpos_seen += 1
            if s & SW_REACHED:
                n_reached_seen += 1
            if (s & (SW_IN_POS | SW_REACHED)) and abs(p - t) > WINDOW_MM:
                viol.append("write %d: setpoint %.3f (from %.3f): status %s, position %.3f mm (%.3f mm off)"
                            % (i, t, pos, sw_text(s), p, abs(p - t)))
            ok, dt, s2, p2 = mb.wait_in_position(t, WINDOW_MM)
            t_wait.append(dt)
            if not ok:
                timeouts.append("write %d: setpoint %.3f not in position within %.0f s (status %s, at %.3f mm)"
                                % (i, t, IN_POSITION_BOUND_S, sw_text(s2), p2))
                if s2 & SW_FAULT:
                    mb.recover_fault()
            pos = mb.pos()
            if (i + 1) % 50 == 0:
                progress("A: %d/%d setpoint writes" % (i + 1, A_SETPOINT_MOVES))
        a1.info("%d writes in %.1f s; reads right after the write showing in_position: %d, target_reached: %d; "
                "of them with the piston > %.1f mm from the new target: %d"
                % (A_SETPOINT_MOVES, time.monotonic() - t_start, n_inpos_seen, n_reached_seen, WINDOW_MM, len(viol)))
        if t_wait:
            a1.info("time to in_position after a write: median %.2f s, max %.2f s"
                    % (sorted(t_wait)[len(t_wait) // 2], max(t_wait)))
        a1.failures += viol + timeouts
        if viol:
            a1.fail("%d of %d reads right after a setpoint write showed in_position/target_reached "
                    "with the piston outside the window of the new target (expected 0)" % (len(viol), A_SETPOINT_MOVES))
        a1.done = True

        # A2: record starts
        mb.unlock(app.unlock_key)
        viol, timeouts, no_ack = [], [], []
        n_inpos_seen = n_reached_seen = 0
        pos = mb.pos()
        for j in range(A_RECORD_STARTS):
            rec = 1 + j % 4
            t = pick_target(rng, pos, A_MOVE_MIN_MM, A_MOVE_MAX_MM, 50.0, 450.0)
            mb.write_record(rec, t, 0.0, 0.0, RECORD_RUNNING_LAW, key=app.unlock_key)
            mb.w1(H_RECORD_SELECT, rec)
            mb.w1(H_CONTROL_WORD, CW_START)
            s = mb.status()          # at once
            p = mb.pos()
            if s & SW_IN_POS:
                n_inpos_seen += 1
            if s & SW_REACHED:
                n_reached_seen += 1
            if (s & (SW_IN_POS | SW_REACHED)) and abs(p - t) > WINDOW_MM:
                viol.append("start %d (record %d, target %.3f, from %.3f): status %s, position %.3f mm (%.3f mm off)"
                            % (j, rec, t, pos, sw_text(s), p, abs(p - t)))
            t0 = time.monotonic()
            while not (mb.status() & SW_ACK) and time.monotonic() - t0 < 1.0:
                time.sleep(0.005)
            if not (mb.status() & SW_ACK) and time.monotonic() - t0 >= 1.0:
                no_ack.append("start %d (record %d): no ack within 1 s" % (j, rec))
            mb.w1(H_CONTROL_WORD, 0)
            ok, dt, s2, p2 = mb.wait_in_position(t, WINDOW_MM)
            if not ok:
                timeouts.append("start %d: record %d (target %.3f) not in position within %.0f s (status %s, at %.3f)"
                                % (j, rec, t, IN_POSITION_BOUND_S, sw_text(s2), p2))
                if s2 & SW_FAULT:
                    mb.recover_fault()
            pos = mb.pos()
        a2.info("%d record starts (records 1-4, speed 0, window 0 = %.1f mm, law 255 = running); reads right "
                "after the start edge showing in_position: %d, target_reached: %d; of them outside the window: %d"
                % (A_RECORD_STARTS, WINDOW_MM, n_inpos_seen, n_reached_seen, len(viol)))
        a2.failures += viol + no_ack + timeouts
        if viol:
            a2.fail("%d of %d reads right after a start edge showed in_position/target_reached with the piston "
                    "outside the window of the record's target (expected 0)" % (len(viol), A_RECORD_STARTS))
        a2.done = True

        # A3: halt short of the target
        pos = mb.pos()
        t = pos + 200.0 if pos + 200.0 <= 480.0 else pos - 200.0
        mb.write_record(5, t, 20.0, 0.0, RECORD_RUNNING_LAW, key=app.unlock_key)
        mb.w1(H_RECORD_SELECT, 5)
        acked, _ = mb.start_edge()
        time.sleep(1.0)  # stays, the stimulus: the halt comes 1 s into the move
        p_halt = mb.pos()
        mb.halt_edge()
        t0 = time.monotonic()
        s = mb.status()
        while s & SW_MOVING and time.monotonic() - t0 < 5.0:
            time.sleep(0.01)
            s = mb.status()
        t_clear = time.monotonic() - t0
        a3.info("record 5: %.3f -> %.3f mm at 20 mm/s, start acked: %s; halt at %.3f mm after 1 s; "
                "moving cleared after %.2f s" % (pos, t, acked, p_halt, t_clear))
        if s & SW_MOVING:
            a3.fail("moving still set %.1f s after the halt (status %s)" % (t_clear, sw_text(s)))
        reads = []
        for _ in range(6):
            s = mb.status()
            p = mb.pos()
            reads.append((s, p))
            time.sleep(0.1)
        for s, p in reads:
            off = abs(p - t)
            if off > WINDOW_MM and (s & SW_IN_POS):
                a3.fail("in_position set with the piston %.3f mm from the record's target (%.3f mm, target %.3f): %s"
                        % (off, p, t, sw_text(s)))
            if off > WINDOW_MM and (s & SW_REACHED):
                a3.fail("target_reached set with the piston %.3f mm from the record's target (%.3f mm, target %.3f): %s"
                        % (off, p, t, sw_text(s)))
            if not (s & SW_HALTED):
                a3.fail("halted not set after the halt (%.3f mm): %s" % (p, sw_text(s)))
        a3.info("status after moving cleared (6 reads over 0.6 s): %s; position %.3f mm, %.3f mm from the target"
                % (", ".join(sorted(set(sw_text(s) for s, _ in reads))), reads[-1][1], abs(reads[-1][1] - t)))
        again = sum(1 for s, _ in reads if s & SW_MOVING)
        if again:
            a3.info("note: moving read 1 again in %d of those 6 reads after it had cleared (not judged here)" % again)
        a3.done = True

        # A4: target_reached in STOP after a completed move
        pos = mb.pos()
        t = pick_target(rng, pos, 40.0, 100.0, 50.0, 450.0)
        mb.wf32(H_SETPOINT, t)
        ok, dt, s, p = mb.wait_in_position(t, WINDOW_MM)
        t0 = time.monotonic()
        while ok and not (s & SW_REACHED) and time.monotonic() - t0 < 2.0:
            time.sleep(0.01)
            s = mb.status()
        a4.info("move %.3f -> %.3f mm completed: %s, status before STOP %s" % (pos, t, ok, sw_text(s)))
        if not ok:
            a4.fail("the move before STOP did not come into position (%s, %.3f mm)" % (sw_text(s), p))
        mb.w1(H_MODE, MODE_STOP)
        s_now = mb.status()
        time.sleep(0.3)  # stays: the status is judged right after the write and 0.3 s later
        s_later = mb.status()
        a4.info("status right after mode := STOP: %s; 0.3 s later: %s" % (sw_text(s_now), sw_text(s_later)))
        for when, s in (("right after the write", s_now), ("0.3 s later", s_later)):
            if s & SW_REACHED:
                a4.fail("target_reached reads 1 in STOP %s (%s)" % (when, sw_text(s)))
            if s & SW_RUN:
                a4.info("note: run_enabled still set %s" % when)
        a4.done = True
    except Exception as e:
        abort_unfinished(checks, e, app)
    finally:
        if mb:
            mb.close()
        app.stop()
    return checks


def abort_unfinished(checks, e, app):
    """A group stopped by an exception: every check it had not finished fails, naming it."""
    for c in checks:
        if not c.done:
            c.fail("aborted: %s: %s" % (type(e).__name__, e))
            c.info(traceback.format_exc().strip().splitlines()[-1])
            c.info("appliance log: " + app.log_tail(4))


# ---------------------------------------------------------------------------------------------
# B. No nuisance following error; a crippled axis still faults
# ---------------------------------------------------------------------------------------------
def group_b(env):
    b1 = Check("B1", "no following_error/warning on any of %d moves that reach their target (4 laws, setpoint and "
                     "record moves at 0/30/100/300 mm/s); every move left standing or cycling beyond following_error_mm "
                     "from its target says so" % (4 * B_MOVES_PER_LAW))
    b2 = Check("B2", "a too-slow axis (flow_saturation=20 mm/s) still faults with a following error")
    checks = [b1, b2]
    results = {}

    def crippled():
        try:
            crippled_fault(env, b2)
        except Exception as e:
            b2.fail("aborted: %s: %s" % (type(e).__name__, e))
            b2.done = True

    def one_law(law):
        results[law] = b_law(env, law)

    # each law on its own appliance, in parallel (the budget), the crippled axis beside them
    threads = [threading.Thread(target=crippled, daemon=True)]
    threads += [threading.Thread(target=one_law, args=(law,), daemon=True) for law in (0, 1, 2, 3)]
    if PARALLEL:
        for th in threads:
            th.start()
        for th in threads:
            th.join(GROUP_JOIN_BOUND_S)
    else:
        for th in threads:
            th.start()
            th.join(GROUP_JOIN_BOUND_S)
    b1.info("law: moves, polls, polls with following_error, polls with warning (not explained by off_target), "
            "moves ending off_target, moves not ended within %.0f s, faults; seconds" % B_MOVE_BOUND_S)
    total = {"reached": 0, "fe": 0, "warn": 0, "faults": 0, "missed": 0, "silent": 0}
    offenders = []
    for law in (0, 1, 2, 3):
        r = results.get(law)
        if r is None:
            b1.fail("law %s: did not finish" % LAWS[law])
            continue
        st, offs, errors = r
        b1.info("%-8s: %d moves, %d polls; %d reached their target, on them: FE %d, warning %d; moves that did not "
                "(standing >= %.0f mm off, or faulted): %d, of them silent %d; cycling %d; off_target %d, not ended %d, "
                "faults %d; %.0f s"
                % (LAWS[law], st["moves"], st["polls"], st["reached"], st["fe"], st["warn"], B_FE_MM, st["missed"], st["silent"],
                   st["cycling"], st["off"], st["unended"], st["faults"], st["seconds"]))
        for line in st["missed_lines"]:
            b1.info("    not reached: " + line)
        for k in total:
            total[k] += st[k]
        offenders += offs
        b1.failures += errors
    if total["fe"] or total["warn"] or total["silent"]:
        b1.fail("on moves that reached their target, polls with following_error: %d, with warning: %d (expected 0, 0); "
                "moves that missed by >= %.0f mm with no following error or fault: %d (expected 0); moves that showed "
                "them: %d" % (total["fe"], total["warn"], B_FE_MM, total["silent"], len(offenders)))
    b1.failures += offenders
    if total["reached"] < B_MIN_REACHED:
        b1.fail("only %d moves reached their target (at least %d, so that 'no nuisance alarm' is judged on enough moves)"
                % (total["reached"], B_MIN_REACHED))
    b1.done = True
    return checks


B_FE_MM = 50.0        # [limits] following_error_mm, the default the B appliances run with
B_MARGIN_MM = 2.0     # where the piston stands is read through noise and a few reads: no verdict within this of the limit
B_MIN_REACHED = int(0.4 * 4 * B_MOVES_PER_LAW)  # pp-ngidz and pp-traj reach nearly all of theirs
B_LATE_ALARM_S = 2.5  # a piston standing beyond the limit: its alarm may follow the law's lag, within the fault's 2 s


def b_law(env, law):
    """B's moves under one law on an appliance of its own: (stats, offending moves, errors)."""
    st = {"moves": 0, "polls": 0, "reached": 0, "fe": 0, "warn": 0, "off": 0, "unended": 0, "faults": 0, "missed": 0,
          "silent": 0, "cycling": 0,
          "missed_lines": [], "seconds": 0.0}
    offenders, errors = [], []
    app = Appliance(env, "B-%s" % LAWS[law])
    mb = None
    t_start = time.monotonic()
    try:
        app.start()
        mb = Mb(app.mb_port)
        mb.w1(H_CONTROL_WORD, 0)
        mb.w1(H_CONTROLLER, law)
        rb = mb.hr(H_CONTROLLER, 1)[0]
        if rb != law:
            errors.append("holding 3 := %d reads back %d" % (law, rb))
        mb.w1(H_MODE, MODE_RUN)
        mb.unlock(app.unlock_key)
        mb.wait_in_position(None, WINDOW_MM, 3.0)
        rng = random.Random(SEED + 10 + law)
        kinds = [("setpoint", None), ("record", 0.0), ("record", 30.0), ("record", 100.0), ("record", 300.0)]
        for k in range(B_MOVES_PER_LAW):
            kind, speed = kinds[k % len(kinds)]
            pos = mb.pos()
            dmax = 150.0 if speed == 30.0 else 300.0
            t = pick_target(rng, pos, 10.0, dmax, 20.0, 480.0)
            label = "%s %s %.1f -> %.1f mm%s" % (LAWS[law], kind, pos, t,
                                                 "" if speed is None else " at %g mm/s" % speed)
            move = {"fe": 0, "warn": 0, "first": None, "t0": time.monotonic()}

            def on_poll(s, move=move):
                st["polls"] += 1
                if s & SW_FOLLOWING:
                    move["fe"] += 1
                if (s & SW_WARNING) and not (s & SW_OFF_TARGET):
                    move["warn"] += 1
                if (s & (SW_FOLLOWING | SW_WARNING)) and not (s & SW_OFF_TARGET) and move["first"] is None:
                    move["first"] = (time.monotonic() - move["t0"], s)

            if kind == "setpoint":
                move["t0"] = time.monotonic()
                mb.wf32(H_SETPOINT, t)
            else:
                rec = 1 + (k % 8)
                mb.write_record(rec, t, speed, 0.0, RECORD_RUNNING_LAW, key=app.unlock_key)
                mb.w1(H_RECORD_SELECT, rec)
                move["t0"] = time.monotonic()
                mb.start_edge(on_poll=on_poll)
            t0 = move["t0"]
            seen_moving, ended, s = False, False, 0
            while time.monotonic() - t0 < B_MOVE_BOUND_S:
                s = mb.status()
                on_poll(s)
                if s & SW_FAULT:
                    break
                if s & SW_MOVING:
                    seen_moving = True
                if seen_moving or time.monotonic() - t0 >= 0.3:
                    if s & SW_IN_POS and abs(mb.pos() - t) <= WINDOW_MM:
                        ended = True
                        break
                    if not (s & SW_MOVING):
                        ended = True
                        break
                time.sleep(B_POLL_S)
            st["moves"] += 1
            if s & SW_OFF_TARGET:
                st["off"] += 1
            faulted = bool(s & SW_FAULT)
            code = mb.ir(I_FAULT_CODE, 1)[0] if faulted else 0
            if not faulted and not ended:
                st["unended"] += 1
            # Where the piston is, as the mean of a few reads (a law cycling at the sampling rate
            # alternates its readings), against the target: the truth the alarm is judged by.
            reads = []
            for _ in range(5):
                reads.append(mb.pos())
                time.sleep(0.01)
            off_by = abs(sum(reads) / len(reads) - t)
            reached = not faulted and ended and off_by <= WINDOW_MM
            stalled = not faulted and ended and off_by >= B_FE_MM + B_MARGIN_MM
            if stalled and not move["fe"]:
                # The expected motion reaches the target with the law's lag: the alarm may come a
                # little after the piston stood. Wait for it, bounded by the fault's own time.
                t1 = time.monotonic()
                while time.monotonic() - t1 < B_LATE_ALARM_S and not (s & (SW_FOLLOWING | SW_FAULT)):
                    time.sleep(B_POLL_S)
                    s = mb.status()
                if s & SW_FOLLOWING:
                    move["fe"] += 1
                    move["first"] = move["first"] or (time.monotonic() - t0, s)
                faulted = bool(s & SW_FAULT)
                code = mb.ir(I_FAULT_CODE, 1)[0] if faulted else 0
            el, s1 = move["first"] if move["first"] else (NAN, 0)
            what = ("%s: %d polls with following_error, %d with warning; first at %.2f s: %s; the piston ends %.1f mm "
                    "from its target (%s)%s" % (label, move["fe"], move["warn"], el, sw_text(s1), off_by, sw_text(s),
                                               ", fault_code %d" % code if faulted else ""))
            if reached:
                st["reached"] += 1
                st["fe"] += move["fe"]
                st["warn"] += move["warn"]
                if move["fe"] or move["warn"]:
                    offenders.append("nuisance alarm on a move that reached its target: " + what)
            elif faulted or stalled:
                st["missed"] += 1
                st["missed_lines"].append(what)
                if not faulted and not move["fe"]:
                    st["silent"] += 1
                    offenders.append("stood >= %.0f mm from its target and said nothing: %s" % (B_FE_MM, what))
            elif not ended:
                # Still moving at the bound: a law cycling about its target (the paper's FF-IDZ on its
                # printed model does at the end stops). Hunting is its own detection, not this one's.
                st["cycling"] += 1
                st["missed_lines"].append("cycling, not ended within %.0f s: %s" % (B_MOVE_BOUND_S, what))
            elif off_by <= B_FE_MM - B_MARGIN_MM and s & SW_FOLLOWING:
                offenders.append("ended %.1f mm off (under following_error_mm) with following_error still set: %s"
                                 % (off_by, what))
            if faulted:
                st["faults"] += 1
                mb.recover_fault()
        progress("B: law %s done in %.0f s" % (LAWS[law], time.monotonic() - t_start))
    except Exception as e:
        errors.append("law %s aborted after %d moves: %s: %s; appliance log: %s"
                      % (LAWS[law], st["moves"], type(e).__name__, e, app.log_tail(3)))
    finally:
        st["seconds"] = time.monotonic() - t_start
        if mb:
            mb.close()
        app.stop()
    return st, offenders, errors


def crippled_fault(env, chk):
    fe_mm, fe_time = 50.0, 2.0
    app = Appliance(env, "B-crippled", limits={"following_error_mm": fe_mm, "following_error_time_s": fe_time},
                    hal_sim={"effects": ["flow_saturation=20"]}, unlock=False)
    mb = None
    try:
        app.start()
        mb = Mb(app.mb_port)
        mb.w1(H_MODE, MODE_RUN)
        mb.wait_in_position(None, WINDOW_MM, 3.0)
        p0 = mb.pos()
        t = p0 + 300.0 if p0 + 300.0 <= 480.0 else p0 - 300.0
        mb.wf32(H_SETPOINT, t)
        t0 = time.monotonic()
        t_fe = t_fault = None
        s = 0
        bound = 10.0
        while time.monotonic() - t0 < bound:
            s = mb.status()
            el = time.monotonic() - t0
            if s & SW_FOLLOWING and t_fe is None:
                t_fe = el
            if s & SW_FAULT:
                t_fault = el
                break
            time.sleep(0.02)
        code = mb.ir(I_FAULT_CODE, 1)[0]
        p = mb.pos()
        chk.info("config: [hal.sim] effects = [\"flow_saturation=20\"], following_error_mm %.0f, "
                 "following_error_time_s %.0f; setpoint %.1f -> %.1f mm" % (fe_mm, fe_time, p0, t))
        chk.info("following_error first seen at %s s, fault_latched at %s s (bound %.0f s), fault_code %d, "
                 "position then %.1f mm, status %s"
                 % (fmt(t_fe, 2), fmt(t_fault, 2), bound, code, p, sw_text(s)))
        if t_fault is None:
            chk.fail("no fault latched within %.0f s (status %s, piston at %.1f mm of %.1f)" % (bound, sw_text(s), p, t))
        elif code != FAULT_FOLLOWING_ERROR:
            chk.fail("fault_code %d, expected %d (following error)" % (code, FAULT_FOLLOWING_ERROR))
        if t_fe is None:
            chk.fail("following_error (bit 5) never seen before the fault")
        elif t_fault is not None and t_fe >= t_fault:
            chk.fail("following_error first seen at %.2f s, not before the fault at %.2f s" % (t_fe, t_fault))
        chk.done = True
    finally:
        if mb:
            mb.close()
        app.stop()


# ---------------------------------------------------------------------------------------------
# C. One record of a move
# ---------------------------------------------------------------------------------------------
class Heartbeat(threading.Thread):
    def __init__(self, port):
        super().__init__(daemon=True)
        self.port = port
        self.paused = threading.Event()
        self.stopped = threading.Event()
        self.errors = 0
        self.value = 1

    def run(self):
        mb = None
        try:
            mb = Mb(self.port)
            while not self.stopped.is_set():
                if not self.paused.is_set():
                    try:
                        mb.wn(H_HEARTBEAT, [(self.value >> 16) & 0xFFFF, self.value & 0xFFFF])
                        self.value += 1
                    except Exception:
                        self.errors += 1
                self.stopped.wait(C_HEARTBEAT_PERIOD_S)
        except Exception:
            self.errors += 1
        finally:
            if mb:
                mb.close()


def c_plan():
    """Kinds of moves, interleaved so that every kind comes early: (kind, law)."""
    head = [("normal", 3), ("cut", 3), ("halt", 3), ("slow", 3), ("record", 3), ("fault", 3),
            ("normal", 1), ("cut", 1), ("halt", 1), ("normal", 2), ("record", 1), ("normal", 0),
            ("normal", 3), ("cut", 3), ("halt", 3), ("record", 2), ("normal", 1), ("slow", 3),
            ("fault", 1), ("normal", 3), ("cut", 3), ("halt", 3), ("record", 3), ("normal", 2),
            ("cut", 1), ("halt", 1), ("normal", 3), ("record", 3), ("normal", 1), ("cut", 3),
            ("halt", 3), ("normal", 3), ("normal", 0), ("record", 1), ("normal", 3), ("normal", 3)]
    return head


def group_c(env):
    c1 = Check("C1", "one record of a move: registers 70-83/141, /api/moves, the run file and a recomputation agree")
    c2 = Check("C2", "`epa tuning runs` agrees with those moves")
    checks = [c1, c2]
    app = Appliance(env, "C", limits={"heartbeat_timeout_s": C_HEARTBEAT_TIMEOUT_S})
    mb = None
    hb = None
    captured = []           # (expect, regs, api_entry or None, api_err)
    try:
        app.start()
        mb = Mb(app.mb_port)
        hb = Heartbeat(app.mb_port)
        hb.start()
        time.sleep(0.3)
        mb.w1(H_CONTROL_WORD, 0)
        mb.w1(H_MODE, MODE_RUN)
        mb.unlock(app.unlock_key)
        mb.wait_in_position(None, WINDOW_MM, 3.0)
        rng = random.Random(SEED + 3)
        last_n = mb.move_number()
        c1.info("heartbeat every %.1f s on its own connection, heartbeat_timeout_s %.1f; moves so far: %d"
                % (C_HEARTBEAT_PERIOD_S, C_HEARTBEAT_TIMEOUT_S, last_n))
        state = {"law": None, "n": last_n}
        t_start = time.monotonic()

        def set_law(law):
            if state["law"] != law:
                mb.w1(H_CONTROLLER, law)
                state["law"] = law

        def capture(expect, bound):
            n = expect["number"]
            m = mb.wait_move_number(n, bound)
            regs = mb.move_regs()
            p_end = mb.pos()
            expect["pos_at_end"] = p_end
            if m < n:
                expect["not_ended"] = "move %d not ended within %.0f s (move_number %d, status %s)" % (
                    n, bound, m, sw_text(mb.status()))
            entry, err = None, "not looked up"
            t0 = time.monotonic()
            while time.monotonic() - t0 < 1.5:
                try:
                    moves = app.http_json("/api/moves").get("moves", [])
                    entry = next((e for e in moves if e.get("number") == n), None)
                    err = None if entry else "no entry with number %d in /api/moves (numbers %s)" % (
                        n, [e.get("number") for e in moves][:25])
                except Exception as e:
                    err = "GET /api/moves: %s" % e
                if entry:
                    break
                time.sleep(0.1)
            captured.append((expect, regs, entry, err))

        def new_expect(kind, law, frm, target, window=WINDOW_MM, speed=None):
            state["n"] += 1
            return {"number": state["n"], "kind": kind, "law": law, "from": frm, "target": target,
                    "window": window, "speed": speed}

        def setpoint_move(kind, law, dmin, dmax):
            set_law(law)
            pos = mb.pos()
            # C judges records, not laws (B does): away from the end stops, where FF-IDZ on the
            # printed model cycles and faults (B reports that), so every law's moves end as moves.
            t = pick_target(rng, pos, dmin, dmax, C_LO_MM, C_HI_MM)
            ex = new_expect(kind, law, pos, t)
            mb.wf32(H_SETPOINT, t)
            return ex

        def record_move(kind, law, rec, t, speed):
            set_law(law)
            mb.write_record(rec, t, speed, 0.0, RECORD_RUNNING_LAW, key=app.unlock_key)
            mb.w1(H_RECORD_SELECT, rec)
            # A new law holds the last setpoint, and after a move that ended off target it moves the
            # piston there while the record is written: the move starts somewhere between the last
            # read before the start edge and the first read after it.
            pos = mb.pos()
            ex = new_expect(kind, law, pos, t, speed=speed)
            acked, _ = mb.start_edge()
            ex["from_bracket"] = (pos, mb.pos())
            if not acked:
                ex["note"] = "start not acknowledged within 1 s"
            return ex

        plan = c_plan()
        i = 0
        while True:
            n_done = len(captured)
            if n_done >= C_MIN_MOVES and i >= len(plan):
                break
            if time.monotonic() - t_start > C_TIME_BUDGET_S:
                c1.fail("time budget of %.0f s used up after %d moves (at least %d wanted): moves end too late "
                        "or the plan is too long" % (C_TIME_BUDGET_S, n_done, C_MIN_MOVES))
                break
            kind, law = plan[i % len(plan)]
            i += 1
            if mb.status() & SW_FAULT:
                mb.recover_fault()
            if kind == "normal":
                ex = setpoint_move("normal", law, 30.0, 250.0)
                capture(ex, MOVE_END_BOUND_S)
            elif kind == "record":
                pos = mb.pos()
                t = pick_target(rng, pos, 30.0, 250.0, 20.0, 480.0)
                speed = rng.choice([0.0, 100.0, 300.0])
                ex = record_move("normal", law, 1 + i % 4, t, speed)
                capture(ex, MOVE_END_BOUND_S)
            elif kind == "cut":
                ex1 = setpoint_move("cut", law, 150.0, 250.0)
                t0 = time.monotonic()
                while time.monotonic() - t0 < 0.15:   # mid-move
                    time.sleep(0.01)
                p = mb.pos()
                ex1["cut_at"] = p
                t2 = pick_target(rng, p, 40.0, 150.0, 20.0, 480.0)
                ex2 = new_expect("normal", law, p, t2)
                ex2["from_approx"] = True             # the piston moves: its from is where the cut found it
                mb.wf32(H_SETPOINT, t2)
                capture(ex1, MOVE_END_BOUND_S)
                capture(ex2, MOVE_END_BOUND_S)
            elif kind == "halt":
                pos = mb.pos()
                t = pick_target(rng, pos, 150.0, 250.0, 20.0, 480.0)
                ex = record_move("halt", law, 5, t, 100.0)
                time.sleep(rng.uniform(0.4, 0.8))
                ex["halt_at"] = mb.pos()
                mb.halt_edge()
                capture(ex, MOVE_END_BOUND_S)
            elif kind == "slow":
                pos = mb.pos()
                if not (pos + 250.0 <= 480.0 or pos - 250.0 >= 20.0):
                    set_law(3)
                    t0p = 100.0 if pos > 250.0 else 400.0
                    ex0 = new_expect("normal", 3, pos, t0p)
                    mb.wf32(H_SETPOINT, t0p)
                    capture(ex0, MOVE_END_BOUND_S)
                    pos = mb.pos()
                t = pos + 250.0 if pos + 250.0 <= 480.0 else pos - 250.0
                ex = record_move("slow", law, 6, t, 30.0)
                capture(ex, SLOW_END_BOUND_S)
            elif kind == "fault":
                pos = mb.pos()
                # At least 150 mm at 30 mm/s (5 s): the heartbeat, stopped 0.8 s in, faults it on its
                # way even with the sanitizer run's 3 s timeout.
                t = pick_target(rng, pos, 150.0, 250.0, 20.0, 480.0)
                ex = record_move("fault", law, 7, t, 30.0)
                time.sleep(0.8)
                hb.paused.set()
                t0 = time.monotonic()
                s = mb.status()
                while not (s & SW_FAULT) and time.monotonic() - t0 < C_HEARTBEAT_TIMEOUT_S + 3.0:
                    time.sleep(0.02)
                    s = mb.status()
                code = mb.ir(I_FAULT_CODE, 1)[0]
                ex["fault"] = (time.monotonic() - t0, code, s)
                capture(ex, MOVE_END_BOUND_S)
                hb.paused.clear()
                time.sleep(2 * C_HEARTBEAT_PERIOD_S)  # stays, the stimulus: the heartbeat stays paused
                mb.recover_fault()
                mb.wait_in_position(None, WINDOW_MM, 3.0)
                state["law"] = mb.hr(H_CONTROLLER, 1)[0]
            if len(captured) // 10 != n_done // 10:
                progress("C: %d moves recorded (%.0f s)" % (len(captured), time.monotonic() - t_start))
        c1.info("%d moves in %.1f s" % (len(captured), time.monotonic() - t_start))
        if hb.errors:
            c1.info("heartbeat write errors: %d" % hb.errors)
        verify_moves(app, c1, captured)
        c1.done = True
        time.sleep(1.0)
        verify_tuning_runs(env, app, c2, captured)
        c2.done = True
    except Exception as e:
        abort_unfinished(checks, e, app)
    finally:
        if hb:
            hb.stopped.set()
            hb.join(3)
        if mb:
            mb.close()
        app.stop()
    return checks


EXPECTED_END = {"normal": ("in_position", "timeout", "off_target"), "cut": ("cut_short",), "halt": ("halted",),
                "fault": ("fault",), "slow": ("in_position",)}
REQUIRED_META = ("move", "from_mm", "step_mm", "target_mm", "move_end", "ess_window_s", "controller", "Ts")


def verify_moves(app, chk, captured):
    kinds = {}
    nmoves_ok = 0
    missing_meta_all = {}
    last_sample = {}
    for ex, regs, entry, api_err in captured:
        kinds[ex["kind"]] = kinds.get(ex["kind"], 0) + 1
        n = ex["number"]
        tag = "move %d (%s, %s, %.2f -> %.2f mm%s)" % (n, ex["kind"], LAWS[ex["law"]], ex["from"], ex["target"],
                                                       "" if ex.get("speed") is None else ", %g mm/s" % ex["speed"])
        fails = []
        if ex.get("not_ended"):
            fails.append(ex["not_ended"])
        if ex.get("note"):
            fails.append(ex["note"])
        if "fault" in ex:
            dt, code, s = ex["fault"]
            if not (s & SW_FAULT):
                fails.append("heartbeat stopped but no fault latched within %.1f s" % dt)
            elif code != FAULT_HEARTBEAT_LOST:
                fails.append("fault_code %d after the heartbeat stopped, expected %d" % (code, FAULT_HEARTBEAT_LOST))
        if regs["number"] != n:
            fails.append("register move_number %d, expected %d (the registers show another move)" % (regs["number"], n))
        reg_end = MOVE_END_NAMES.get(regs["move_end_code"], "code %d" % regs["move_end_code"])
        # the run file
        path, meta, y = wait_run_file(app, n)
        if path is None:
            fails.append("run file: %s" % y)
        else:
            last_sample[n] = y[-1]
            missing = [k for k in REQUIRED_META if k not in meta]
            for k in missing:
                missing_meta_all[k] = missing_meta_all.get(k, 0) + 1
            if missing:
                fails.append("run file %s lacks metadata %s" % (os.path.basename(path), ", ".join(missing)))
            if meta.get("_schema") != "epa-run/1":
                fails.append("run file schema line %r, expected 'epa-run/1'" % meta.get("_schema"))
            Ts = meta_float(meta, "Ts")
            m_from = meta_float(meta, "from_mm")
            m_step = meta_float(meta, "step_mm")
            m_target = meta_float(meta, "target_mm")
            if isnan(m_target) and not isnan(m_from) and not isnan(m_step):
                m_target = m_from + m_step
            m_end = meta.get("move_end")
            ess_w = meta_float(meta, "ess_window_s")
            if meta.get("move") not in (None, str(n)) and meta_float(meta, "move") != n:
                fails.append("run file move=%s, expected %d" % (meta.get("move"), n))
            if meta.get("controller") != LAWS[ex["law"]]:
                fails.append("run file controller=%s, expected %s (the law selected for the move)"
                             % (meta.get("controller"), LAWS[ex["law"]]))
            if not close(m_target, ex["target"], TOL_MM + 5e-4):
                fails.append("run file target_mm %s, commanded %.4f" % (fmt(m_target), ex["target"]))
            if not isnan(m_from) and not isnan(m_step) and not close(m_from + m_step, m_target, TOL_MM):
                fails.append("run file from_mm %s + step_mm %s != target_mm %s" % (fmt(m_from), fmt(m_step), fmt(m_target)))
            if not close(m_from, regs["from_mm"], TOL_MM):
                fails.append("from_mm: run file %s, register %s" % (fmt(m_from), fmt(regs["from_mm"])))
            tol_from = 10.0 if ex.get("from_approx") or ex["kind"] == "cut" else 1.0  # cut: the piston at speed
            if y and not close(y[0], m_from, TOL_MM):
                fails.append("the run file's first sample %.4f is not its from_mm %s" % (y[0], fmt(m_from)))
            before, after = ex.get("from_bracket", (ex["from"], ex["from"]))
            if not (min(before, after) - tol_from <= m_from <= max(before, after) + tol_from):
                fails.append("from_mm %s, but the piston read %.3f mm just before the move%s"
                             % (fmt(m_from), before, "" if after == before else " and %.3f mm just after its start" % after))
            if m_end is not None and m_end != reg_end:
                fails.append("move_end: register %s (%d), run file %s" % (reg_end, regs["move_end_code"], m_end))
            end_name = m_end if m_end is not None else reg_end
            if end_name not in EXPECTED_END[ex["kind"]]:
                fails.append("move_end %s, expected %s for a %s move" % (end_name, " or ".join(EXPECTED_END[ex["kind"]]), ex["kind"]))
            if isnan(Ts) or isnan(m_from) or isnan(m_target) or abs(m_target - m_from) <= 0:
                fails.append("cannot recompute: Ts %s, from %s, target %s" % (fmt(Ts), fmt(m_from), fmt(m_target)))
            else:
                mine = recompute(y, Ts, m_from, m_target, end_name, ess_w)
                if isnan(ess_w) and end_name != "halted":
                    fails.append("ess not recomputable without ess_window_s")
                tols = {"rise_s": TOL_S, "settling_s": TOL_S, "ess_mm": TOL_MM, "overshoot_pct": TOL_PCT}
                for key, tol in tols.items():
                    r = regs[key]
                    a = api_float(entry, key) if entry else None
                    if not (isnan(ess_w) and key == "ess_mm") and not close(mine[key], r, tol):
                        fails.append("%s: recomputed %s, register %s" % (key, fmt(mine[key]), fmt(r)))
                    if entry is not None and not close(a, r, tol):
                        fails.append("%s: /api/moves %s, register %s" % (key, fmt(a), fmt(r)))
                # coverage: from the start ...
                if abs(y[0] - m_from) > 1.0:
                    why = ""
                    prev_last = last_sample.get(n - 1)
                    if prev_last is not None and abs(prev_last - m_from) < 1e-3:
                        why = ("; from_mm is move %d's last sample and this file starts one cycle later (%.0f mm/s "
                               "between the two)" % (n - 1, abs(y[0] - m_from) / Ts))
                    fails.append("the file's first sample %.3f mm is %.3f mm from from_mm %.3f (it does not start "
                                 "where the move started%s)" % (y[0], abs(y[0] - m_from), m_from, why))
                # ... to the end
                if end_name == "in_position":
                    k = max(1, int(round(IN_POSITION_TIME_S / Ts)))
                    worst = max(abs(v - m_target) for v in y[-k:])
                    if worst > ex["window"]:
                        fails.append("in_position end but the last %d samples reach %.3f mm from the target (window %.1f mm)"
                                     % (k, worst, ex["window"]))
                if ex["kind"] == "slow":
                    dur = len(y) * Ts
                    need = abs(m_target - m_from) / ex["speed"]
                    if dur < 0.9 * need or abs(y[-1] - m_target) > ex["window"]:
                        fails.append("slow record: the file covers %.2f s (the move needs %.1f s) and ends at %.3f mm, "
                                     "%.3f mm from the target" % (dur, need, y[-1], abs(y[-1] - m_target)))
        # registers against the commanded move and the API
        if not close(regs["to_mm"], ex["target"], TOL_MM):
            fails.append("move_to_mm register %s, commanded %.4f" % (fmt(regs["to_mm"]), ex["target"]))
        if entry is None:
            fails.append(api_err or "no /api/moves entry")
        else:
            if law_name(entry.get("controller")) != LAWS[ex["law"]]:
                fails.append("/api/moves controller %s, expected %s" % (entry.get("controller"), LAWS[ex["law"]]))
            for key in ("from_mm", "to_mm"):
                if not close(api_float(entry, key), regs[key], TOL_MM):
                    fails.append("%s: /api/moves %s, register %s" % (key, fmt(api_float(entry, key)), fmt(regs[key])))
            if "move_end" in entry:
                ae = entry["move_end"]
                ae = MOVE_END_NAMES.get(ae, ae) if isinstance(ae, int) else ae
                if ae != reg_end:
                    fails.append("move_end: /api/moves %s, register %s" % (ae, reg_end))
        ex["regs"] = regs
        if fails:
            chk.fail("%s: %s" % (tag, "; ".join(fails)))
        else:
            nmoves_ok += 1
    chk.info("moves by kind: %s" % ", ".join("%s %d" % kv for kv in sorted(kinds.items())))
    chk.info("moves whose registers, /api/moves, run file and recomputation all agree: %d of %d"
             % (nmoves_ok, len(captured)))
    if missing_meta_all:
        chk.info("run-file metadata missing: %s" % ", ".join("%s in %d files" % kv for kv in sorted(missing_meta_all.items())))
    if len(captured) < C_MIN_MOVES:
        chk.fail("only %d moves recorded, at least %d wanted" % (len(captured), C_MIN_MOVES))
    # a few of the figures, for the record
    for ex, regs, entry, _ in captured[:6]:
        chk.info("move %d %-6s: end %s, rise %s s, settling %s s, e_ss %s mm, overshoot %s %%"
                 % (regs["number"], ex["kind"], MOVE_END_NAMES.get(regs["move_end_code"], regs["move_end_code"]),
                    fmt(regs["rise_s"], 3), fmt(regs["settling_s"], 3), fmt(regs["ess_mm"], 4),
                    fmt(regs["overshoot_pct"], 3)))


def printed_tol(s):
    try:
        return 0.5 * 10.0 ** decimal.Decimal(s).as_tuple().exponent
    except (decimal.InvalidOperation, TypeError):
        return 0.0


def parse_printed(s):
    s = s.strip()
    if s in ("-", "nan", "NaN", "never", "n/a", ""):
        return NAN, 0.0
    try:
        return float(s), printed_tol(s)
    except ValueError:
        return None, 0.0


def verify_tuning_runs(env, app, chk, captured):
    out, used = None, None
    for opt in ("--db", "--store"):
        cmd = [env.binary, "tuning", opt, app.db, "runs", "--limit", "1000"]
        try:
            r = subprocess.run(cmd, cwd=app.dir, capture_output=True, text=True, timeout=60)
        except subprocess.TimeoutExpired:
            chk.fail("`%s` did not finish within 60 s" % " ".join(cmd[1:]))
            return
        if r.returncode == 0:
            out, used = r.stdout, cmd
            break
        chk.info("`epa %s` exited %d: %s" % (" ".join(cmd[1:]), r.returncode, (r.stderr or r.stdout).strip()[:200]))
    if out is None:
        chk.fail("`epa tuning runs` failed with --db and with --store")
        return
    chk.info("ran `epa %s`: %d lines" % (" ".join(used[1:]).replace(app.db, "<db>"), len(out.splitlines())))
    rows = {}
    for line in out.splitlines():
        m = re.search(r"move-(\d+)-", line)
        if m:
            rows.setdefault(int(m.group(1)), line)
    if not rows:
        chk.fail("no row of `epa tuning runs` names a move's run file (move-NNNN-...); its output began: %r"
                 % out[:400])
        return
    ok = 0
    for ex, regs, entry, _ in captured:
        n = ex["number"]
        line = rows.get(n)
        if line is None:
            chk.fail("move %d: no row in `epa tuning runs`" % n)
            continue
        fails = []
        ctrl = next((w for w in line.split() if w in LAW_CODES), None)
        if ctrl != LAWS[ex["law"]]:
            fails.append("controller %s, expected %s" % (ctrl, LAWS[ex["law"]]))
        m = re.search(r"(\S+)\s*->\s*(\S+)\s*mm", line)
        fields = {}
        if m:
            fields["from_mm"], fields["to_mm"] = m.group(1), m.group(2)
        for key, pat in (("rise_s", r"rise\s+(\S+)\s*s\b"), ("settling_s", r"settling\s+(\S+)\s*s\b"),
                         ("ess_mm", r"e_ss\s+(\S+)\s*mm"), ("overshoot_pct", r"overshoot\s+(\S+)\s*%")):
            mm = re.search(pat, line)
            if mm:
                fields[key] = mm.group(1)
        for key in ("from_mm", "to_mm", "rise_s", "settling_s", "ess_mm"):
            if key not in fields:
                fails.append("no %s in the row" % key)
        tols = {"from_mm": TOL_MM, "to_mm": TOL_MM, "rise_s": TOL_S, "settling_s": TOL_S, "ess_mm": TOL_MM,
                "overshoot_pct": TOL_PCT}
        for key, txt in fields.items():
            v, ptol = parse_printed(txt)
            if v is None:
                fails.append("%s %r is not a number" % (key, txt))
            elif not close(v, regs[key], tols[key] + ptol):
                fails.append("%s %s, register %s" % (key, txt, fmt(regs[key])))
        if fails:
            chk.fail("move %d: %s  [row: %s]" % (n, "; ".join(fails), line.strip()))
        else:
            ok += 1
    chk.info("rows that agree with the registers: %d of %d moves" % (ok, len(captured)))
    chk.info("columns assumed: time, controller, 'from -> to mm', 'rise X s', 'settling X s', 'e_ss X mm' "
             "('-' = NaN), the run file's path; an 'overshoot X %%' column is compared when present")


# ---------------------------------------------------------------------------------------------
# D. Laws change only when asked
# ---------------------------------------------------------------------------------------------
def group_d(env):
    d1 = Check("D1", "a record naming another law (pp-traj) runs with it and leaves holding 3 at 2 (pp-ffidz)")
    d2 = Check("D2", "the following plain setpoint move runs, and is labelled, pp-ffidz")
    d3 = Check("D3", "every change of holding 3 is in GET /api/audit, and no other change of the law")
    checks = [d1, d2, d3]
    app = Appliance(env, "D")
    mb = None
    try:
        app.start()
        mb = Mb(app.mb_port)
        my_changes = []
        mb.w1(H_CONTROL_WORD, 0)
        mb.w1(H_MODE, MODE_RUN)
        mb.wait_in_position(None, WINDOW_MM, 3.0)
        before = mb.hr(H_CONTROLLER, 1)[0]
        for law in (1, 2):              # pp-ngidz, then pp-ffidz: two changes of the running law
            old = mb.hr(H_CONTROLLER, 1)[0]
            mb.w1(H_CONTROLLER, law)
            if old != law:
                my_changes.append((old, law))
            time.sleep(0.1)
        now = mb.hr(H_CONTROLLER, 1)[0]
        d1.info("holding 3 was %d, written 1 then 2, reads %d" % (before, now))
        if now != 2:
            d1.fail("holding 3 reads %d after writing 2" % now)
        mb.unlock(app.unlock_key)
        n0 = mb.move_number()
        pos = mb.pos()
        t = pos + 150.0 if pos + 150.0 <= 480.0 else pos - 150.0
        mb.write_record(7, t, 0.0, 0.0, 3, key=app.unlock_key)
        mb.w1(H_RECORD_SELECT, 7)
        acked, _ = mb.start_edge()
        reads, not2 = 0, []
        t0 = time.monotonic()
        m = mb.move_number()
        while m < n0 + 1 and time.monotonic() - t0 < MOVE_END_BOUND_S:
            v = mb.hr(H_CONTROLLER, 1)[0]
            reads += 1
            if v != 2:
                not2.append((round(time.monotonic() - t0, 2), v))
            time.sleep(0.05)
            m = mb.move_number()
        after = mb.hr(H_CONTROLLER, 1)[0]
        d1.info("record 7: %.1f -> %.1f mm, law field 3 (pp-traj), start acked %s; move %d ended after %.2f s; "
                "holding 3 read %d times during the move, %d times not 2; afterwards %d"
                % (pos, t, acked, n0 + 1, time.monotonic() - t0, reads, len(not2), after))
        if m < n0 + 1:
            d1.fail("the record's move did not end within %.0f s (move_number %d)" % (MOVE_END_BOUND_S, m))
        if not2:
            d1.fail("holding 3 read other than 2 during the record's move: %s" % not2[:10])
        if after != 2:
            d1.fail("holding 3 reads %d after the record's move, expected 2" % after)
        check_move_label(app, mb, d1, n0 + 1, "pp-traj")
        d1.done = True

        # D2: a plain setpoint move
        pos = mb.pos()
        t2 = pos - 100.0 if pos - 100.0 >= 20.0 else pos + 100.0
        mb.wf32(H_SETPOINT, t2)
        m = mb.wait_move_number(n0 + 2, MOVE_END_BOUND_S)
        after2 = mb.hr(H_CONTROLLER, 1)[0]
        d2.info("setpoint %.1f -> %.1f mm: move %d ended: %s; holding 3 afterwards %d"
                % (pos, t2, n0 + 2, m >= n0 + 2, after2))
        if m < n0 + 2:
            d2.fail("the setpoint move did not end within %.0f s" % MOVE_END_BOUND_S)
        if after2 != 2:
            d2.fail("holding 3 reads %d, expected 2" % after2)
        check_move_label(app, mb, d2, n0 + 2, "pp-ffidz")
        try:
            st = app.http_json("/api/status")
            d2.info("/api/status controller: %s" % st.get("controller"))
            if law_name(st.get("controller")) != "pp-ffidz":
                d2.fail("/api/status says controller %s after the moves, expected pp-ffidz" % st.get("controller"))
        except Exception as e:
            d2.info("GET /api/status: %s" % e)
        d2.done = True

        # D3: the audit log
        entries = app.http_json("/api/audit").get("entries", [])
        law_entries = [e for e in entries if e.get("point") == "controller"]
        d3.info("audit: %d entries, %d for point 'controller': %s"
                % (len(entries), len(law_entries),
                   ["%s->%s (%s)" % (law_name(e.get("old_value")), law_name(e.get("new_value")), e.get("source"))
                    for e in law_entries]))
        unmatched = list(law_entries)
        for old, new in my_changes:
            hit = next((e for e in unmatched if law_name(e.get("new_value")) == LAWS[new]
                        and law_name(e.get("old_value")) in (LAWS[old], "None")), None)
            if hit is None:
                d3.fail("my change of holding 3 from %s to %s is not in /api/audit" % (LAWS[old], LAWS[new]))
            else:
                unmatched.remove(hit)
                if not str(hit.get("source", "")).startswith("modbus 127.0.0.1"):
                    d3.fail("audit entry for %s -> %s has source %r, expected modbus 127.0.0.1:..."
                            % (LAWS[old], LAWS[new], hit.get("source")))
        for e in unmatched:
            d3.fail("audit has a change of the law that no client asked for: %s" % e)
        d3.info("changes made by writing holding 3: %s"
                % ", ".join("%s -> %s" % (LAWS[o], LAWS[n]) for o, n in my_changes))
        d3.done = True
    except Exception as e:
        abort_unfinished(checks, e, app)
    finally:
        if mb:
            mb.close()
        app.stop()
    return checks


def check_move_label(app, mb, chk, n, law):
    regs = mb.move_regs()
    if regs["number"] != n:
        chk.info("note: the move registers show move %d (expected %d)" % (regs["number"], n))
    path, meta, y = wait_run_file(app, n)
    if path is None:
        chk.fail("move %d: run file: %s" % (n, y))
    else:
        chk.info("move %d run file %s: controller=%s, move_end=%s"
                 % (n, os.path.basename(path), meta.get("controller"), meta.get("move_end")))
        if meta.get("controller") != law:
            chk.fail("move %d: run file controller=%s, expected %s" % (n, meta.get("controller"), law))
    try:
        moves = app.http_json("/api/moves").get("moves", [])
        e = next((x for x in moves if x.get("number") == n), None)
        if e is None:
            chk.fail("move %d: no /api/moves entry" % n)
        else:
            chk.info("move %d /api/moves controller: %s" % (n, e.get("controller")))
            if law_name(e.get("controller")) != law:
                chk.fail("move %d: /api/moves controller %s, expected %s" % (n, e.get("controller"), law))
    except Exception as ex:
        chk.fail("GET /api/moves: %s" % ex)


# ---------------------------------------------------------------------------------------------
# Main
# ---------------------------------------------------------------------------------------------
class Env:
    def __init__(self, binary, src, tmp):
        self.binary, self.src, self.tmp = binary, src, tmp
        self._ports = []
        self._lock = threading.Lock()

    def take_ports(self, n):
        with self._lock:
            if len(self._ports) < n:
                self._ports += free_ports(16)
            taken, self._ports = self._ports[:n], self._ports[n:]
            return taken


def wait_for_binary(path):
    """The binary may be being rebuilt: wait (bounded) until it exists, is stable and runs."""
    t0 = time.monotonic()
    last = None
    announced = False
    checks = 0
    while time.monotonic() - t0 < BINARY_WAIT_S:
        checks += 1
        try:
            st = os.stat(path)
            sig = (st.st_size, st.st_mtime)
            if os.access(path, os.X_OK) and sig == last and time.time() - st.st_mtime > 3:
                return True
            last = sig
        except OSError:
            last = None
        if not announced and checks >= 2:
            progress("waiting for %s to exist and stay unchanged (bounded %.0f s)" % (path, BINARY_WAIT_S))
            announced = True
        time.sleep(2.0)
    return False


def main(argv):
    if len(argv) != 3:
        print("usage: first_day_test.py <epa binary> <source dir>")
        return 2
    binary_arg, src = os.path.abspath(argv[1]), os.path.abspath(argv[2])
    signal.signal(signal.SIGTERM, _on_signal)
    signal.signal(signal.SIGINT, _on_signal)
    sys.setswitchinterval(0.001)
    for p in ("registers/epa.csv", "web"):
        if not os.path.exists(os.path.join(src, p)):
            print("source dir %s has no %s" % (src, p))
            print("0 passed, 1 failed")
            return 1
    if not wait_for_binary(binary_arg):
        print("FAIL: %s did not appear (or kept changing) within %.0f s" % (binary_arg, BINARY_WAIT_S))
        print("0 passed, 1 failed")
        return 1
    tmp = tempfile.mkdtemp(prefix="epa-first-day-")
    binary = os.path.join(tmp, "epa")
    version = "?"
    for _ in range(5):      # copy it, so that a rebuild during the run cannot swap it under us
        try:
            shutil.copy2(binary_arg, binary)
            version = subprocess.run([binary, "--version"], capture_output=True, text=True, timeout=20).stdout.strip()
            if version:
                break
        except (OSError, subprocess.SubprocessError):
            pass
        time.sleep(3)
    print("first_day_test: %s (%s), source %s, work dir %s" % (binary_arg, version or "version unknown", src, tmp))
    env = Env(binary, src, tmp)
    groups = [("A", group_a), ("B", group_b), ("C", group_c), ("D", group_d)]
    results = {}
    t_all = time.monotonic()

    def run_group(name, fn):
        t0 = time.monotonic()
        try:
            results[name] = fn(env)
        except Exception as e:
            c = Check(name, "group %s" % name)
            c.fail("aborted: %s: %s" % (type(e).__name__, e))
            results[name] = [c]
        progress("group %s finished in %.1f s" % (name, time.monotonic() - t0))

    if PARALLEL:
        threads = [threading.Thread(target=run_group, args=g, daemon=True) for g in groups]
        for th in threads:
            th.start()
        deadline = time.monotonic() + GROUP_JOIN_BOUND_S
        for th in threads:
            th.join(max(0.0, deadline - time.monotonic()))
    else:
        for g in groups:
            run_group(*g)
    checks = []
    for name, _ in groups:
        if name in results:
            checks += results[name]
        else:
            c = Check(name, "group %s" % name)
            c.fail("did not finish within %.0f s" % GROUP_JOIN_BOUND_S)
            checks.append(c)
    _cleanup_procs()
    print()
    for c in checks:
        print(c.render())
        print()
    passed = sum(1 for c in checks if c.passed)
    failed = len(checks) - passed
    print("elapsed %.1f s" % (time.monotonic() - t_all))
    try:
        os.remove(binary)
        if failed == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print("logs, databases and run files kept in %s" % tmp)
    except OSError:
        pass
    print("%d passed, %d failed" % (passed, failed))
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
