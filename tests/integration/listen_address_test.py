#!/usr/bin/env python3
"""The listen addresses as configured are what the appliance binds and what its log says, checked
from outside with raw sockets and plain HTTP (no project code on the client side):

    listen_address_test.py <epa binary> <source dir>

  * [modbus] and [web] address = "::1": a Modbus read over IPv6 loopback is answered, the page's
    /api/status too (with any_address_may_command true and the start-up WARNING in the log), the
    log names [::1]:port for both, and 127.0.0.1 on the Modbus port is refused (nothing listens);
  * address = "::" takes IPv6 and IPv4 (Modbus and web): with write_clients = ["127.0.0.1"] a
    setpoint written over IPv4 is accepted (the peer is compared by its IPv4 address), one over ::1
    gets exception 04, no WARNING is logged and /api/status says any_address_may_command false;
  * address = "999.1.1.1" (once bound as 255.255.255.255) is refused at start, naming key and value.

Skipped (exit 77) when the machine has no IPv6 loopback.
"""
import http.client
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time

UNIT = 1
FAILURES = []


def check(ok, what):
    print(("PASS " if ok else "FAIL ") + what)
    if not ok:
        FAILURES.append(what)


def free_port(family, host):
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return s.getsockname()[1]


def ipv6_loopback():
    try:
        with socket.socket(socket.AF_INET6, socket.SOCK_STREAM) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


def modbus_request(host, port, pdu, transaction=1):
    """One Modbus TCP request over a raw socket; the answer's PDU, or None when none came."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.settimeout(2.0)
        s.connect((host, port))
        s.sendall(struct.pack(">HHHB", transaction, 0, len(pdu) + 1, UNIT) + pdu)
        head = b""
        while len(head) < 7:
            chunk = s.recv(7 - len(head))
            if not chunk:
                return None
            head += chunk
        length = struct.unpack(">H", head[4:6])[0]
        body = b""
        while len(body) < length - 1:
            chunk = s.recv(length - 1 - len(body))
            if not chunk:
                return None
            body += chunk
        return body


def read_setpoint_pdu():
    return struct.pack(">BHH", 3, 0, 2)  # FC3, holding 0, 2 registers: setpoint_mm (float32)


def write_setpoint_pdu(mm):
    return struct.pack(">BHHB", 16, 0, 2, 4) + struct.pack(">f", mm)


class Serve:
    """`epa serve` on the configuration given; its log in the folder; stopped by its PID."""

    def __init__(self, epa, folder, name, config_text):
        self.config = os.path.join(folder, name + ".toml")
        self.log_path = os.path.join(folder, name + ".log")
        with open(self.config, "w") as f:
            f.write(config_text)
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen([epa, "serve", "--config", self.config, "--mode", "stop"], stdout=self.log,
                                     stderr=subprocess.STDOUT)

    # Until `text` is in the log (or the process ended). The start is waited for by the
    # supervisor's whole "running" line: the word alone comes earlier, in the model-health
    # monitor's "the running tuning set ..." line, before the listeners are up.
    def wait_for(self, text, timeout_s=15.0):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if text in self.log_text():
                return True
            if self.proc.poll() is not None:
                return text in self.log_text()
            time.sleep(0.05)
        return False

    def log_text(self):
        self.log.flush()
        with open(self.log_path) as f:
            return f.read()

    def stop(self):
        if self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.kill(self.proc.pid, signal.SIGKILL)
                self.proc.wait(timeout=5)
        self.log.close()
        return self.proc.returncode


def base_config(folder, src, name):
    return (f'[store]\npath = "{os.path.join(folder, name + ".db")}"\n'
            f'[recorder]\ndirectory = "{os.path.join(folder, name + "-runs")}"\n'
            "[log]\nstatus_interval_s = 0\n"
            "[loop]\nrealtime_priority = 0\nlock_memory = false\ncpu_dma_latency_us = -1\n")


def ipv6_only(epa, src, folder):
    mb_port, web_port = free_port(socket.AF_INET6, "::1"), free_port(socket.AF_INET6, "::1")
    app = Serve(epa, folder, "v6", base_config(folder, src, "v6") +
                f'[modbus]\naddress = "::1"\nport = {mb_port}\nregister_map = "{os.path.join(src, "registers", "epa.csv")}"\n'
                f'[web]\naddress = "::1"\nport = {web_port}\nstatic_dir = "{os.path.join(src, "web")}"\n')
    try:
        check(app.wait_for("[info] running\n"), "address = \"::1\": the appliance starts")
        log = app.log_text()
        check(f"modbus: listening on [::1]:{mb_port}" in log, f"the log names the Modbus socket as bound: [::1]:{mb_port}")
        check(f"web: listening on [::1]:{web_port}" in log, f"the log names the web socket as bound: [::1]:{web_port}")
        check("any address may command motion over Modbus: set [modbus] write_clients" in log,
              "no write_clients: the start-up WARNING says any address may command motion")
        answer = modbus_request("::1", mb_port, read_setpoint_pdu())
        check(answer is not None and answer[0] == 3 and answer[1] == 4, f"a Modbus read over [::1]:{mb_port} is answered: {answer!r}")
        conn = http.client.HTTPConnection("::1", web_port, timeout=5)
        conn.request("GET", "/api/status")
        r = conn.getresponse()
        body = r.read()
        status = json.loads(body) if r.status == 200 else {}
        conn.close()
        check(r.status == 200 and status.get("any_address_may_command") is True,
              f"GET /api/status over [::1]:{web_port}: {r.status}, any_address_may_command = {status.get('any_address_may_command')!r}")
        try:
            modbus_request("127.0.0.1", mb_port, read_setpoint_pdu())
            refused = False
        except OSError:
            refused = True
        check(refused, f"127.0.0.1:{mb_port} is not listened on (only ::1 is bound)")
    finally:
        app.stop()


def dual_stack(epa, src, folder):
    mb_port, web_port = free_port(socket.AF_INET6, "::"), free_port(socket.AF_INET6, "::")
    app = Serve(epa, folder, "dual", base_config(folder, src, "dual") +
                f'[modbus]\naddress = "::"\nport = {mb_port}\nregister_map = "{os.path.join(src, "registers", "epa.csv")}"\n'
                f'write_clients = ["127.0.0.1"]\n[web]\naddress = "::"\nport = {web_port}\nstatic_dir = "{os.path.join(src, "web")}"\n')
    try:
        check(app.wait_for("[info] running\n"), "address = \"::\": the appliance starts")
        log = app.log_text()
        check(f"modbus: listening on [::]:{mb_port}" in log, f"the log names [::]:{mb_port}")
        check("any address may command motion" not in log, "write_clients set: no WARNING")
        v4 = modbus_request("127.0.0.1", mb_port, write_setpoint_pdu(120.0))
        check(v4 is not None and v4[0] == 16, f"a setpoint written over IPv4 to \"::\" from 127.0.0.1 (on write_clients) is accepted: {v4!r}")
        v6 = modbus_request("::1", mb_port, write_setpoint_pdu(130.0))
        check(v6 is not None and v6[0] == 0x90 and v6[1] == 4, f"the same over ::1 (not on write_clients) gets exception 04: {v6!r}")
        for host in ("127.0.0.1", "::1"):
            conn = http.client.HTTPConnection(host, web_port, timeout=5)
            conn.request("GET", "/api/status")
            r = conn.getresponse()
            status = json.loads(r.read()) if r.status == 200 else {}
            conn.close()
            check(r.status == 200 and status.get("any_address_may_command") is False,
                  f"web on \"::\" answers over {host}: {r.status}, any_address_may_command = {status.get('any_address_may_command')!r}")
    finally:
        app.stop()


def refused_address(epa, src, folder):
    app = Serve(epa, folder, "bad", base_config(folder, src, "bad") + '[modbus]\naddress = "999.1.1.1"\n[web]\nenabled = false\n')
    try:
        app.proc.wait(timeout=15)
    except subprocess.TimeoutExpired:
        pass
    code = app.stop()
    with open(app.log_path) as f:
        log = f.read()
    check(code not in (0, None) and "modbus.address '999.1.1.1' is not an IP address" in log,
          f"address = \"999.1.1.1\" is refused at start (exit {code}): {log.strip().splitlines()[-1] if log.strip() else ''}")


def main():
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if not ipv6_loopback():
        print("SKIP: this machine has no IPv6 loopback (::1 cannot be bound)")
        sys.exit(77)
    with tempfile.TemporaryDirectory(prefix="epa-listen.") as folder:
        ipv6_only(epa, src, folder)
        dual_stack(epa, src, folder)
        refused_address(epa, src, folder)
    if FAILURES:
        print(f"{len(FAILURES)} check(s) failed")
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
