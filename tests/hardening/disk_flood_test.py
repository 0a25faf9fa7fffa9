#!/usr/bin/env python3
"""Disk flooding by clients with no key, from outside: raw Modbus/TCP frames over plain sockets
(no project code on the client side). One client writes record_s = 3600 in a loop, another
setpoints in a loop, for 60 s (20 s under a sanitizer): the first half in STOP, where every
record is a 60 s file, the second in RUN, where each setpoint starts a move and a move file. Judged from outside the appliance,
every second: the run files stay within [recorder] quota_mb, the database and its WAL within a
bound that follows from [store] audit_max_rows, the log within a few lines a second, and the store
saving throughout (store_ok set, saved_counter catching up with change_counter). At the end the
audit table holds no more rows than the retention allows.

usage: disk_flood_test.py <epa binary> <source dir>
"""
import os
import random
import re
import shutil
import socket
import sqlite3
import struct
import subprocess
import sys
import tempfile
import threading
import time

HOST = "127.0.0.1"
QUOTA_MB = 0.05 if os.environ.get("EPA_SANITIZER_RUN") else 0.25  # reached within the flood either way
AUDIT_MAX_ROWS = 20000
FLOOD_S = float(os.environ.get("EPA_DISK_FLOOD_S", 20 if os.environ.get("EPA_SANITIZER_RUN") else 60))


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


class Modbus:
    """A minimal Modbus/TCP client on one socket: FC2, FC4, FC16; exceptions as negative codes."""

    def __init__(self, port):
        self.sock = socket.create_connection((HOST, port), timeout=3)
        self.tid = 0

    def close(self):
        self.sock.close()

    def _call(self, pdu):
        self.tid = (self.tid + 1) & 0xFFFF
        self.sock.sendall(struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, 1) + pdu)
        head = self._read(7)
        tid, _, length, _ = struct.unpack(">HHHB", head)
        body = self._read(length - 1)
        if tid != self.tid:
            raise IOError("transaction id %d, expected %d" % (tid, self.tid))
        return body

    def _read(self, n):
        data = b""
        while len(data) < n:
            chunk = self.sock.recv(n - len(data))
            if not chunk:
                raise IOError("connection closed")
            data += chunk
        return data

    def write_float(self, address, value):
        body = self._call(struct.pack(">BHHB", 16, address, 2, 4) + struct.pack(">f", value))
        return -body[1] if body[0] & 0x80 else 0

    def write_u16(self, address, value):
        body = self._call(struct.pack(">BHHBH", 16, address, 1, 2, value))
        return -body[1] if body[0] & 0x80 else 0

    def read_input_u32(self, address):
        body = self._call(struct.pack(">BHH", 4, address, 2))
        if body[0] & 0x80:
            raise IOError("exception %d reading input %d" % (body[1], address))
        return struct.unpack(">I", body[2:6])[0]

    def read_discrete(self, address):
        body = self._call(struct.pack(">BHH", 2, address, 1))
        if body[0] & 0x80:
            raise IOError("exception %d reading discrete %d" % (body[1], address))
        return body[2] & 1


def registers(source_dir):
    """name -> (table, address) from the shipped register map (the file an integrator reads)."""
    out = {}
    with open(os.path.join(source_dir, "registers", "epa.csv")) as f:
        for line in f:
            if line.startswith("#") or line.startswith("name,"):
                continue
            cols = line.split(",")
            if len(cols) > 2:
                out[cols[0]] = (cols[1], int(cols[2]))
    return out


def configuration(source_dir, work):
    with open(os.path.join(source_dir, "config", "epa.toml")) as f:
        text = f.read()
    text = text.replace('"../', '"' + source_dir + "/")
    text = re.sub(r"(?m)^quota_mb = .*$", "quota_mb = %g" % QUOTA_MB, text)
    text = re.sub(r"(?m)^audit_max_rows = .*$", "audit_max_rows = %d" % AUDIT_MAX_ROWS, text)
    for key in ("quota_mb", "audit_max_rows"):
        if not re.search(r"(?m)^%s = " % key, text):
            fail("the shipped config/epa.toml has no %s to set" % key)
    path = os.path.join(work, "epa.toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def start_appliance(epa, config, work):
    log = open(os.path.join(work, "serve.log"), "w")
    proc = subprocess.Popen([epa, "serve", "--config", config, "--modbus-port", "0", "--web-port", "0", "--mode", "stop",
                             "--record-dir", os.path.join(work, "runs"), "--db", os.path.join(work, "epa.db")],
                            stdout=log, stderr=subprocess.STDOUT, cwd=work)
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        with open(os.path.join(work, "serve.log")) as f:
            m = re.search(r"modbus: listening on [^ ]*:(\d+)", f.read())
        if m:
            return proc, int(m.group(1))
        if proc.poll() is not None:
            break
        time.sleep(0.1)
    proc.kill()
    fail("the appliance did not start:\n" + open(os.path.join(work, "serve.log")).read())


def bytes_in(folder, names=None):
    total = 0
    for name in os.listdir(folder) if os.path.isdir(folder) else []:
        if names is None or re.match(names, name):
            try:
                total += os.path.getsize(os.path.join(folder, name))
            except FileNotFoundError:
                pass  # rotated out between the listing and the size
    return total


def flood(port, write, stop, counts):
    client = Modbus(port)
    try:
        while not stop.is_set():
            code = write(client)
            counts[code] = counts.get(code, 0) + 1
    finally:
        client.close()


def main():
    epa, source_dir = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    regs = registers(source_dir)
    work = tempfile.mkdtemp(prefix="epa-disk-flood-")
    proc, port = start_appliance(epa, configuration(source_dir, work), work)
    try:
        run_flood(port, regs, work)
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
    audit_rows = sqlite3.connect(os.path.join(work, "epa.db")).execute("SELECT count(*) FROM audit_log").fetchone()[0]
    # The retention runs every 1000 saved items: it may be that many rows behind at the end.
    if audit_rows > AUDIT_MAX_ROWS + 1000:
        fail("the audit log holds %d rows, above audit_max_rows %d (+1000 between retention runs)" % (audit_rows, AUDIT_MAX_ROWS))
    print("audit rows at the end: %d (audit_max_rows %d)" % (audit_rows, AUDIT_MAX_ROWS))
    shutil.rmtree(work)
    print("PASS")


def run_flood(port, regs, work):
    setpoint, record = regs["setpoint_mm"][1], regs["record_s"][1]
    stop = threading.Event()
    record_counts, setpoint_counts = {}, {}
    rng = random.Random(7)
    threads = [threading.Thread(target=flood, args=(port, lambda c: c.write_float(record, 3600.0), stop, record_counts)),
               threading.Thread(target=flood, args=(port, lambda c: c.write_float(setpoint, rng.uniform(10, 490)), stop,
                                                      setpoint_counts))]
    for t in threads:
        t.start()
    watcher = Modbus(port)
    quota = QUOTA_MB * 1024 * 1024
    # A run file is written whole, then the oldest go: for a moment the quota plus the newest file
    # (a 60 s record: 12,000 samples of about 24 bytes, under 0.5 MiB).
    worst_runs = worst_db = 0
    lagging = 0
    newest_record = 0  # record files are numbered: a number above the files left means the oldest went
    moves_seen = False  # a move file in some look (the quota may rotate them all out by the end)
    started = time.monotonic()
    in_run = False
    try:
        while time.monotonic() - started < FLOOD_S:
            time.sleep(1.0)
            if not in_run and time.monotonic() - started >= FLOOD_S / 2:
                # The flood fills the loop's command queue: busy (06) means "try again", as an HMI does.
                code = -6
                for _ in range(100):
                    code = watcher.write_u16(regs["mode"][1], 1)
                    if code != -6:
                        break
                    time.sleep(0.01)
                if code != 0:
                    fail("mode RUN refused in the middle of the flood (code %d)" % code)
                in_run = True
            names = os.listdir(os.path.join(work, "runs")) if os.path.isdir(os.path.join(work, "runs")) else []
            newest_record = max([newest_record] + [int(n[7:11]) for n in names if re.match(r"record-\d{4}-", n)])
            moves_seen = moves_seen or any(n.startswith("move-") for n in names)
            runs = bytes_in(os.path.join(work, "runs"), r"(move|record|excite)-.*\.csv$")
            db = bytes_in(work, r"epa\.db")
            worst_runs, worst_db = max(worst_runs, runs), max(worst_db, db)
            if runs > quota + 512 * 1024:
                fail("the run files hold %d bytes after %.0f s, above the %g MiB quota" % (runs, time.monotonic() - started, QUOTA_MB))
            if not watcher.read_discrete(regs["store_ok"][1]):
                fail("store_ok fell to 0 during the flood: the store stopped saving")
            accepted = watcher.read_input_u32(regs["change_counter"][1])
            time.sleep(0.5)
            saved = watcher.read_input_u32(regs["saved_counter"][1])
            lagging = lagging + 1 if saved < accepted else 0
            if lagging >= 3:
                fail("saved_counter %d stayed behind change_counter %d for 3 looks: the store is not keeping up" % (saved, accepted))
    finally:
        stop.set()
        for t in threads:
            t.join(10)
        watcher.close()
    elapsed = time.monotonic() - started
    run_files = [n for n in os.listdir(os.path.join(work, "runs")) if n.endswith(".csv")]
    record_files = [n for n in run_files if n.startswith("record-")]
    log_lines = sum(1 for _ in open(os.path.join(work, "serve.log")))
    print("flood of %.0f s: record_s writes %s, setpoint writes %s (code: count; 0 accepted, -4 refused)" %
          (elapsed, record_counts, setpoint_counts))
    print("worst run files %.2f MiB (quota %g MiB; %d files at the end), worst database+WAL %.1f MiB, log %d lines" %
          (worst_runs / 2**20, QUOTA_MB, len(run_files), worst_db / 2**20, log_lines))
    print("record files: %d written, %d left" % (newest_record, len(record_files)))
    if newest_record <= len(record_files):
        fail("no record file was rotated out: the flood never reached the %g MiB quota, so it was not tested" % QUOTA_MB)
    if not moves_seen and not any(n.startswith("move-") for n in run_files):
        fail("no move file: the flood in RUN made no moves")
    accepted_records = record_counts.get(0, 0)
    if accepted_records > elapsed / 5.0 + 2:
        fail("%d record requests accepted in %.0f s: more than one per min_interval_s (5 s)" % (accepted_records, elapsed))
    if setpoint_counts.get(0, 0) < 100:
        fail("only %d setpoint writes accepted: the flood did not reach the store" % setpoint_counts.get(0, 0))
    # 20,000 rows of ~100 bytes and their index, with the WAL's checkpoint size on top.
    if worst_db > 32 * 1024 * 1024:
        fail("the database and its WAL reached %.1f MiB" % (worst_db / 2**20))
    if log_lines > 40 + 4 * elapsed:
        fail("the log has %d lines after %.0f s of flood: repeated lines are not throttled" % (log_lines, elapsed))


if __name__ == "__main__":
    main()
