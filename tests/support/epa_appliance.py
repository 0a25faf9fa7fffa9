"""Shared by the Python tests that run the appliance as a process: Debian's pymodbus (re-executing
under /usr/bin/python3 when another python3 comes first in PATH), float/uint32 encoding with an
explicit word order, a free loopback port, and `epa serve` as a child process that is stopped by
its PID (SIGTERM, SIGKILL after 5 s) or killed outright, and can be started again on the same
folder, port and database; and a supervising client's heartbeat on its own connection.
"""
import os
import sys

# CMake calls `python3`; on a machine where another python3 (pyenv, a venv) comes first in PATH,
# Debian's python3-pymodbus lives only under /usr/bin/python3: run there instead.
try:
    import pymodbus  # noqa: F401
except ImportError:
    debian_python = "/usr/bin/python3"
    if os.path.realpath(sys.executable) != os.path.realpath(debian_python) and os.path.exists(debian_python) \
            and not os.environ.get("EPA_INTEROP_REEXEC"):
        os.environ["EPA_INTEROP_REEXEC"] = "1"
        os.execv(debian_python, [debian_python, os.path.abspath(sys.argv[0])] + sys.argv[1:])  # the test script
    sys.exit("FAIL: pymodbus is not importable by %s; install python3-pymodbus and python3-serial-asyncio "
             "(scripts/install-deps.sh)" % sys.executable)

import ctypes
import shutil
import signal
import socket
import struct
import subprocess
import tempfile
import threading
import time

from pymodbus.client import ModbusTcpClient
from pymodbus.pdu import ExceptionResponse

HOST = "127.0.0.1"
UNIT = 1
UNLOCK_KEY = "5e3a9c17d24b086f"  # [modbus] unlock_key of the test appliances: 16 hex digits
UNLOCK_ADDRESS = 9               # the `unlock` key64 of registers/epa.csv: holding 9-12


def key_words(key=UNLOCK_KEY):
    """The four registers of a key64, most significant first."""
    v = int(key, 16)
    return [(v >> s) & 0xFFFF for s in (48, 32, 16, 0)]


def unlock(client, key=UNLOCK_KEY):
    """Writes the key to `unlock` in one FC16; the pymodbus answer."""
    return client.write_registers(UNLOCK_ADDRESS, key_words(key), slave=UNIT)


# ---- float32 encoding with an explicit word order ----
def f32_words(value, order):
    hi, lo = struct.unpack(">HH", struct.pack(">f", value))
    return [hi, lo] if order == "ABCD" else [lo, hi]


def f32_value(words, order):
    hi, lo = (words[0], words[1]) if order == "ABCD" else (words[1], words[0])
    return struct.unpack(">f", struct.pack(">HH", hi, lo))[0]


def u32_words(value):
    return [(value >> 16) & 0xFFFF, value & 0xFFFF]


def u32_value(words):
    return (words[0] << 16) | words[1]


def i16_value(word):
    return word - 0x10000 if word & 0x8000 else word


# ---- points by name, through a register map file (epa-registers/1) ----
def read_register_map(path):
    """{name: (table, address, type, word_order)} of a register map file."""
    points = {}
    with open(path) as f:
        for line in f:
            fields = line.rstrip("\n").split(",")
            if line.startswith("#") or len(fields) < 5 or fields[0] == "name":
                continue
            points[fields[0]] = (fields[1], int(fields[2]), fields[3], fields[4] or "ABCD")
    return points


def read_point(client, points, name):
    """A holding or input point's value, decoded by its type (float32, uint32, uint16)."""
    table, address, kind, order = points[name]
    count = 2 if kind in ("float32", "uint32") else 1
    read = client.read_input_registers if table == "input" else client.read_holding_registers
    words = read(address, count, slave=UNIT).registers
    if kind == "float32":
        return f32_value(words, order)
    return u32_value(words) if kind == "uint32" else words[0]


def write_point(client, points, name, value):
    """Writes a holding point (float32 or uint16) in one request; the pymodbus answer."""
    table, address, kind, order = points[name]
    if kind == "float32":
        return client.write_registers(address, f32_words(value, order), slave=UNIT)
    return client.write_register(address, int(value), slave=UNIT)


# ---- the appliance as a child process ----
def wait_until(predicate, timeout_s, every_s=0.01):
    """Polls `predicate` until it returns something true (returned) or `timeout_s` has passed (its
    last value is returned)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(every_s)
    return predicate()


def wait_until_steady(read, tolerance, timeout_s, every_s=0.1):
    """Polls `read` every `every_s` until two readings in a row differ by at most `tolerance` (at
    rest) or `timeout_s` has passed; returns whether it came to rest."""
    deadline = time.monotonic() + timeout_s
    last = read()
    while time.monotonic() < deadline:
        time.sleep(every_s)
        now = read()
        if abs(now - last) <= tolerance:
            return True
        last = now
    return False


def stop_process(proc, grace_s=5.0):
    """Stops a child by its PID: SIGTERM, SIGKILL after `grace_s`."""
    proc.terminate()
    try:
        proc.wait(timeout=grace_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=grace_s)


class Checks:
    """PASS/FAIL lines and the failures, for a test script's exit code."""

    def __init__(self):
        self.failures = []

    def __call__(self, ok, what):
        print(("PASS: " if ok else "FAIL: ") + what, flush=True)
        if not ok:
            self.failures.append(what)
        return ok


def free_port():
    with socket.socket() as s:
        s.bind((HOST, 0))
        return s.getsockname()[1]


def _die_with_parent():
    # If this test is killed (ctest timeout), the kernel sends the appliance SIGTERM.
    try:
        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except Exception:
        pass


class Appliance:
    """`epa serve` on a free loopback port with the given register map and extra config, its data
    (database, runs, log) in a fresh temporary folder."""

    def __init__(self, epa, register_map, extra_config="", start=True, args=(), web_static_dir=None, db=None, modbus_extra="",
                 web_extra=""):
        """`args` are added to `epa serve`'s command line; with `web_static_dir` the status page runs on
        a free port too (`web_port`); `db` puts the database elsewhere (a small file system)."""
        self.epa = epa
        self.dir = tempfile.mkdtemp(prefix="epa-test.")
        self.port = free_port()
        self.config = os.path.join(self.dir, "epa.toml")
        self.db = db or os.path.join(self.dir, "epa.db")
        self.args = list(args)
        self.env = None  # the environment of `epa serve` (None: this one's)
        self.web_port = free_port() if web_static_dir else None
        web = (f'[web]\naddress = "127.0.0.1"\nport = {self.web_port}\nstatic_dir = "{web_static_dir}"\n'
               + web_extra if web_static_dir else "[web]\nenabled = false\n")
        self.log_path = os.path.join(self.dir, "epa.log")
        self.proc = None
        self.log = None
        self.client = None
        with open(self.config, "w") as f:
            f.write("# written by tests/support/epa_appliance.py\n"
                    "[modbus]\n"
                    'address = "127.0.0.1"\n'
                    f"port = {self.port}\n"
                    f'register_map = "{register_map}"\n'
                    f'unlock_key = "{UNLOCK_KEY}"\n'
                    + modbus_extra + web +
                    "[log]\n"
                    "status_interval_s = 0\n"
                    "[recorder]\n"
                    f'directory = "{os.path.join(self.dir, "runs")}"\n'
                    "[store]\n"
                    f'path = "{self.db}"\n' + extra_config)
        if start:
            self.start()

    def start(self):
        """Starts `epa serve` (again) and waits until it answers Modbus reads."""
        self.log = open(self.log_path, "a")
        self.proc = subprocess.Popen([self.epa, "serve", "--config", self.config, "--mode", "stop"] + self.args, stdout=self.log,
                                     stderr=subprocess.STDOUT, preexec_fn=_die_with_parent, env=self.env)
        self.client = None
        try:
            self._wait_ready(10.0)
        except BaseException:
            self.stop()
            self.remove()
            raise

    def _wait_ready(self, timeout_s):
        """Polls (bounded) until a TCP connect succeeds and a Modbus read answers."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"epa serve exited with status {self.proc.returncode} during start-up:\n{self.log_text()}")
            try:
                with socket.create_connection((HOST, self.port), timeout=0.2):
                    pass
                break
            except OSError:
                time.sleep(0.05)
        else:
            raise RuntimeError(f"epa serve did not accept connections on {HOST}:{self.port} within {timeout_s} s:\n"
                               f"{self.log_text()}")
        self.client = ModbusTcpClient(HOST, port=self.port, timeout=2, retries=1)
        if not self.client.connect():
            raise RuntimeError(f"pymodbus could not connect to {HOST}:{self.port}")
        while time.monotonic() < deadline:
            # Any Modbus answer will do (a map may have nothing at input 0: exception 02 is an answer).
            rr = self.client.read_input_registers(0, 1, slave=UNIT)
            if not rr.isError() or isinstance(rr, ExceptionResponse):
                return
            time.sleep(0.05)
        raise RuntimeError(f"epa serve did not answer Modbus reads within {timeout_s} s:\n{self.log_text()}")

    def stop(self):
        """Stops by PID: SIGTERM, SIGKILL after 5 s. Returns the exit status."""
        if self.client is not None:
            self.client.close()
            self.client = None
        status = self.proc.poll()
        if status is None:
            self.proc.terminate()
            try:
                status = self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                print(f"epa serve (pid {self.proc.pid}) ignored SIGTERM for 5 s: SIGKILL", file=sys.stderr)
                self.proc.kill()
                status = self.proc.wait(timeout=5)
        self.log.close()
        return status

    def kill(self):
        """SIGKILL: no shutdown code runs, as in a crash or a power cut of the process."""
        if self.client is not None:
            self.client.close()
            self.client = None
        self.proc.kill()
        self.proc.wait(timeout=5)
        self.log.close()

    def log_text(self):
        if not self.log.closed:
            self.log.flush()
        with open(self.log_path) as f:
            return f.read()

    def remove(self):
        shutil.rmtree(self.dir, ignore_errors=True)




class Heartbeat:
    """What a supervising HMI does while it is connected: increments the `heartbeat` uint32 (holding
    6-7 of registers/epa.csv, ABCD) every `every_s` on its own connection, in a thread. `pause()` and
    `resume()` stop and restart the beat (a client that went away); `close()` ends the thread.
    `errors` lists the writes that were not answered normally."""

    def __init__(self, port, address=6, every_s=0.2):
        self.address, self.every_s = address, every_s
        self.client = ModbusTcpClient(HOST, port=port, timeout=2, retries=1)
        if not self.client.connect():
            raise RuntimeError(f"heartbeat: pymodbus could not connect to {HOST}:{port}")
        self.count = 0
        self.errors = []
        self.beating = threading.Event()
        self.beating.set()
        self.stopping = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while not self.stopping.is_set():
            if self.beating.is_set():
                self.count += 1
                rr = self.client.write_registers(self.address, u32_words(self.count & 0xFFFFFFFF), slave=UNIT)
                if rr.isError():
                    self.errors.append(str(rr))
            self.stopping.wait(self.every_s)

    def pause(self):
        self.beating.clear()

    def resume(self):
        self.beating.set()

    def close(self):
        self.stopping.set()
        self.thread.join(timeout=5)
        self.client.close()
