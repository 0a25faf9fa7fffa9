#!/usr/bin/env python3
"""Modbus/TCP Security against clients nobody here wrote: Debian's pymodbus 3.0 (its TLS client,
AsyncModbusTlsClient) and `openssl s_client` carrying raw Modbus frames, with certificates made by
`epa certs` and checked by TLS libraries that share none of our code.

    modbus_tls_test.py <epa binary> <source dir>

One appliance with plain Modbus and [modbus_tls] on free loopback ports, the default role table
(viewer read, operator operate, engineer tune), a CRL with one client revoked:
  - each role reads; a viewer's write is refused with exception 04 and never audited; an
    operator writes the setpoint but not a tuning point, and sends no unlock; an engineer writes a
    tuning point without the unlock key; the audit log names each writer's certificate subject;
  - openssl s_client: a read (FC3) and a write refused by role, frames as bytes;
  - refused in the handshake, and logged with the reason: no certificate, a certificate of
    another CA, a revoked one, one whose role is not in the table; plain Modbus still answers;
  - with [modbus] enabled = false, the secure port alone serves.
pymodbus 3.0's ModbusTlsClient frames without the MBAP header by default (the specification keeps
it: framer=ModbusSocketFramer), and its synchronous client waits on the socket for bytes TLS has
already decrypted (an answer read in two parts never completes): the asyncio client is used.
Exit 0 when every check passes.
"""
import asyncio
import os
import socket
import sqlite3
import ssl
import struct
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, UNIT, Appliance, Checks, f32_value, f32_words, free_port, key_words, stop_process  # noqa: E402

from modbus_tls import client_context, make_pki, tls_section  # noqa: E402
from pymodbus.client import AsyncModbusTlsClient  # noqa: E402
from pymodbus.framer.socket_framer import ModbusSocketFramer  # noqa: E402
from pymodbus.pdu import ExceptionResponse  # noqa: E402

SETPOINT = 0     # holding, float32 ABCD (registers/epa.csv)
M_R = 20         # holding, float32: a tuning point
UNLOCK = 9       # holding, key64


def make_test_pki(epa, root):
    """The plant's CA with clients of each role, one revoked, one with a role not in the table;
    and another CA with a client of its own."""
    return make_pki(epa, root, [("view", "viewer"), ("hmi", "operator"), ("eng", "engineer"), ("gone", "operator"), ("guest", "guest")],
                    revoked=["gone"])


async def session(port, ctx, steps):
    """Connects pymodbus's TLS client and runs `steps(client)`; its result."""
    client = AsyncModbusTlsClient(HOST, port=port, sslctx=ctx, server_hostname="localhost", timeout=3, retries=0,
                                  framer=ModbusSocketFramer)
    await client.connect()
    try:
        return await steps(client)
    finally:
        await client.close()


def exception_code(response):
    return response.exception_code if isinstance(response, ExceptionResponse) else None


async def role_checks(port, pki, check):
    async def viewer(c):
        read = await c.read_holding_registers(SETPOINT, 2, slave=UNIT)
        write = await c.write_registers(SETPOINT, f32_words(120.0, "ABCD"), slave=UNIT)
        return read, write
    read, write = await session(port, client_context(pki, name="view"), viewer)
    check(not read.isError(), f"a viewer reads the setpoint ({read})")
    check(exception_code(write) == 4, f"a viewer's setpoint write is refused with exception 04 ({write})")

    async def operator(c):
        write = await c.write_registers(SETPOINT, f32_words(123.0, "ABCD"), slave=UNIT)
        back = await c.read_holding_registers(SETPOINT, 2, slave=UNIT)
        tuning = await c.write_registers(M_R, f32_words(1.5, "ABCD"), slave=UNIT)
        unlock = await c.write_registers(UNLOCK, key_words(), slave=UNIT)
        return write, back, tuning, unlock
    write, back, tuning, unlock = await session(port, client_context(pki, name="hmi"), operator)
    check(not write.isError() and f32_value(back.registers, "ABCD") == 123.0, f"an operator writes the setpoint ({write}, {back})")
    check(exception_code(tuning) == 4, f"an operator's tuning write is refused with exception 04 ({tuning})")
    check(exception_code(unlock) == 4, f"the unlock key is refused on the secure port: the role decides ({unlock})")

    async def engineer(c):
        tuning = await c.write_registers(M_R, f32_words(1.5, "ABCD"), slave=UNIT)
        back = await c.read_holding_registers(M_R, 2, slave=UNIT)
        return tuning, back
    tuning, back = await session(port, client_context(pki, name="eng"), engineer)
    check(not tuning.isError() and f32_value(back.registers, "ABCD") == 1.5,
          f"an engineer writes a tuning point without the unlock key ({tuning}, {back})")


def s_client(port, pki, name, frame, wait_s=1.0):
    """`openssl s_client` with the client `name`'s certificate: sends `frame`, returns what came back."""
    cmd = ["openssl", "s_client", "-quiet", "-no_ign_eof", "-connect", f"{HOST}:{port}", "-CAfile", os.path.join(pki, "ca.pem"),
           "-cert", os.path.join(pki, name + ".pem"), "-key", os.path.join(pki, name + ".key")]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    proc.stdin.write(frame)
    proc.stdin.flush()
    time.sleep(wait_s)  # s_client has no "answer complete": the answer is read after a pause, then stdin ends it
    proc.stdin.close()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    return proc.stdout.read()


def s_client_checks(port, pki, check):
    read = s_client(port, pki, "view", bytes.fromhex("00070000000601" "03" "0000" "0002"))
    check(len(read) == 13 and read[:2] == b"\x00\x07" and read[7] == 3 and read[8] == 4,
          f"s_client, viewer: FC3 of 2 registers answered with 4 bytes ({read.hex()})")
    write = s_client(port, pki, "view", bytes.fromhex("00080000000b01" "10" "0000" "0002" "04") + bytes(f32_words_bytes(50.0)))
    check(write == bytes.fromhex("000800000003019004"), f"s_client, viewer: FC16 refused with exception 04 ({write.hex()})")


def f32_words_bytes(value):
    return b"".join(w.to_bytes(2, "big") for w in f32_words(value, "ABCD"))


def refused(port, ctx, source):
    """Whether the server refuses this client (from the loopback address `source`): the handshake,
    or the first exchange after it (TLS 1.3 finishes the client's side before the server has
    checked its certificate), fails."""
    try:
        with socket.create_connection((HOST, port), timeout=3, source_address=(source, 0)) as raw:
            with ctx.wrap_socket(raw, server_hostname="localhost") as s:
                s.sendall(bytes.fromhex("000900000006010300000002"))
                return s.recv(64) == b""
    except (ssl.SSLError, ConnectionError, socket.timeout):
        return True


def refusal_checks(app, port, pki, other, check):
    cases = [("no certificate", client_context(pki), "certificate"),
             ("a certificate of another CA", client_context(pki, other, "hmi"), "unable to get local issuer certificate"),
             ("a revoked certificate", client_context(pki, name="gone"), "certificate revoked"),
             ("a role not in the table", client_context(pki, name="guest"), 'role "guest" is not in the role table')]
    # Each from its own loopback address: refusals are logged once per address, then held back.
    for n, (what, ctx, reason) in enumerate(cases):
        check(refused(port, ctx, f"127.0.0.{10 + n}"), f"{what}: refused in the handshake")
        deadline = time.monotonic() + 3
        while reason not in app.log_text() and time.monotonic() < deadline:
            time.sleep(0.05)
        check(reason in app.log_text(), f"{what}: the log says why ('{reason}')")
    for n in range(3):  # the same client again: held back
        refused(port, cases[2][1], "127.0.0.12")
    lines = [line for line in app.log_text().splitlines() if "127.0.0.12 refused" in line]
    check(len(lines) == 1, f"a refused address's next refusals are not logged within its back-off ({len(lines)} lines)")


def vanishing_clients(port, pki, check, app):
    """Clients that send a request and reset the connection before the answer: the answer's write
    fails (EPIPE), which must close that connection, not end the appliance (SIGPIPE)."""
    ctx = client_context(pki, name="view")
    try:
        for _ in range(30):
            s = ctx.wrap_socket(socket.create_connection((HOST, port), timeout=3), server_hostname="localhost")
            s.sendall(bytes.fromhex("000a00000006010300000002") * 20)
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # close sends RST
            s.close()
    except OSError as e:
        print(f"a vanishing client's connect failed: {e}")
    time.sleep(0.3)
    check(app.proc.poll() is None, "clients that reset before their answers leave the appliance running")


def cpu_ticks(pid):
    fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])  # utime + stime


def half_record_costs_nothing(port, pki, check, app):
    """A client that sends part of a TLS record and stops: the server waits on the socket for the
    rest; it must not poll without waiting (that spun a core)."""
    ctx = client_context(pki, name="view")
    incoming, outgoing = ssl.MemoryBIO(), ssl.MemoryBIO()
    tls = ctx.wrap_bio(incoming, outgoing, server_hostname="localhost")
    with socket.create_connection((HOST, port), timeout=3) as raw:
        while True:  # the handshake through memory, so that the record can be cut by hand
            try:
                tls.do_handshake()
                break
            except ssl.SSLWantReadError:
                raw.sendall(outgoing.read())
                incoming.write(raw.recv(65536))
        raw.sendall(outgoing.read())
        tls.write(bytes.fromhex("000b00000006010300000002"))
        record = outgoing.read()
        raw.sendall(record[:len(record) // 3])
        time.sleep(0.3)
        before = cpu_ticks(app.proc.pid)
        time.sleep(2.0)
        spent = cpu_ticks(app.proc.pid) - before
        check(spent < 40, f"a third of a record waiting costs the appliance {spent} ticks of CPU in 2 s (< 40; a spin takes ~200)")
        raw.sendall(record[len(record) // 3:])
        answer = b""
        while len(answer) < 13:
            incoming.write(raw.recv(65536))
            try:
                answer += tls.read(64)
            except ssl.SSLWantReadError:
                pass
        check(answer[:2] == b"\x00\x0b" and answer[7] == 3, f"... and the rest of the record brings the answer ({answer.hex()})")


def tls12_reconnect(port, pki, check):
    """A TLS 1.2 client that offers its last session when it reconnects gets a whole handshake."""
    ctx = client_context(pki, name="view")
    ctx.maximum_version = ssl.TLSVersion.TLSv1_2
    session = None
    for attempt in range(2):
        try:
            with ctx.wrap_socket(socket.create_connection((HOST, port), timeout=3), server_hostname="localhost", session=session) as s:
                s.sendall(bytes.fromhex("000c00000006010300000002"))
                answer = s.recv(64)
                session = s.session
        except (ssl.SSLError, OSError) as e:
            answer = repr(e).encode()
        check(answer[:2] == b"\x00\x0c", f"TLS 1.2, connection {attempt + 1} (offering its session the second time) is answered ({answer[:80]})")


def audit_checks(db_path, check):
    db = sqlite3.connect(db_path)
    rows = db.execute("SELECT source, point, new_value FROM audit_log ORDER BY id").fetchall()
    db.close()
    check(any(p == "setpoint_mm" and v == 123.0 and "/CN=hmi" in s and "(operator)" in s for s, p, v in rows),
          f"the operator's setpoint is audited with its certificate's subject and role ({rows})")
    check(any(p == "m_r" and v == 1.5 and "/CN=eng" in s for s, p, v in rows), "the engineer's tuning write is audited with its subject")
    check(not any("/CN=view" in s for s, _, _ in rows), "nothing a viewer sent is audited")
    check(not any(p == "unlock" for _, p, _ in rows), "no unlock is audited: none was taken")


def secure_only_checks(epa, reg_map, pki, check):
    """[modbus] enabled = false: the appliance serves Modbus/TCP Security alone."""
    port = free_port()
    app = Appliance(epa, reg_map, start=False, modbus_extra="enabled = false\n", extra_config=tls_section(pki, port))
    log = app.log = open(app.log_path, "w")
    proc = subprocess.Popen([epa, "serve", "--config", app.config, "--mode", "stop"], stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 10
        while "[info] running\n" not in app.log_text() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.05)
        text = app.log_text()
        check("modbus-tls: listening on" in text and "modbus: listening on" not in text,
              "with [modbus] enabled = false only the secure listener starts")

        async def read(c):
            return await c.read_holding_registers(SETPOINT, 2, slave=UNIT)
        r = asyncio.run(session(port, client_context(pki, name="view"), read))
        check(not r.isError(), f"... and answers ({r})")
        with socket.socket() as s:
            check(s.connect_ex((HOST, app.port)) != 0, "... and the plain port is closed")
    finally:
        stop_process(proc)
        log.close()
        app.remove()


def main():
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    reg_map = os.path.join(src, "registers", "epa.csv")
    check = Checks()
    root = Appliance(epa, reg_map, start=False)  # a temporary folder for the certificates
    pki, other = make_test_pki(epa, root.dir)
    port = free_port()
    app = Appliance(epa, reg_map, extra_config=tls_section(pki, port))
    try:
        check(f"modbus-tls: listening on 127.0.0.1:{port}" in app.log_text(), "the secure listener is logged with its port")
        asyncio.run(role_checks(port, pki, check))
        s_client_checks(port, pki, check)
        refusal_checks(app, port, pki, other, check)
        vanishing_clients(port, pki, check, app)
        half_record_costs_nothing(port, pki, check, app)
        tls12_reconnect(port, pki, check)
        r = app.client.read_holding_registers(SETPOINT, 2, slave=UNIT)
        check(not r.isError(), "plain Modbus still answers beside the secure port")
    finally:
        app.stop()
    audit_checks(app.db, check)
    app.remove()
    secure_only_checks(epa, reg_map, pki, check)
    root.remove()
    print(f"{len(check.failures)} failed" if check.failures else "all passed")
    return 1 if check.failures else 0


if __name__ == "__main__":
    sys.exit(main())
