#!/usr/bin/env python3
"""Hostile clients on the Modbus/TCP Security port ([modbus_tls]), while a legitimate TLS client polls.

    tls_abuse_test.py <epa binary> <source dir>

One appliance with plain Modbus and [modbus_tls] on free loopback ports, the shipped slot limits
(max_clients 16, max_clients_per_address 4, shared by both ports) and handshake_timeout_s 3.
Throughout, a legitimate HMI (its own process, Python's ssl, an operator's certificate, from
127.0.0.2) reads 10 holding registers (FC3) every 100 ms on one persistent connection, reconnecting
when it is dropped, and records each poll's answer time (a reconnect and its handshake count in
it); after each poll it reads modbus_clients (input 126), the appliance's own count of its clients.
Meanwhile, one attacker address each (127.0.0.x, raw sockets and asyncio; nothing of the project's
code):
  garbage     .3   3 s of connects that send noise, a 16 KiB blob, an HTTP request, a plain Modbus
                   frame, a record announcing 65535 bytes, an SSLv2-style hello, an alert, noise then
                   a ClientHello, a ClientHello with bytes flipped, a ClientHello then noise, 3 bytes,
                   nothing: each closed by the appliance (within handshake_timeout_s + 1 s); and a
                   ClientHello followed at once by a reset (the appliance answers a client gone)
  truncated   .4   4 connections send half a ClientHello, then nothing
  slow        .5   4 connections send a ClientHello a byte every 500 ms: both closed
                   handshake_timeout_s after the connect (measured: 3.0-4.0 s)
  at the cap  .6-.9  slow handshakes fill the slots: .6, .7, .8 open 5 each (16 with the HMI: full),
                   then .9 opens 8 at once and keeps exactly its share (4), the others closed at once;
                   then the address holding the most opens 4 more and gains nothing, nobody else
                   loses (counted on the appliance's side in /proc/net/tcp); then 8 s of 8 slow
                   handshakes per address reconnecting 100 ms after each close: the appliance never
                   counts more than max_clients
  wrong CA    .10  20 connects with a certificate of another CA: each refused
  renegotiate .1   `openssl s_client -tls1_2` reads once (a raw FC3 frame), then asks for a
                   renegotiation ("R"): refused (no_renegotiation), and the connection ends
  stalled     .12  a viewer (a valid certificate) sends 3 bytes of a record and stalls: the appliance
                   waits for the socket, it does not spin (under 0.5 s of CPU in 2 s)
Then: at least 95 % of the HMI's polls answered within 1 s; the appliance answers a fresh TLS
client and a plain one; each attacker address has one refusal line in the log (once per address,
with a back-off longer than this test), and the log stays short; SIGTERM ends it with 0.
Loopback only, every loop bounded (about 20 s of attacks); the appliance is stopped by its PID.
Exit 0 when every check passes.
"""
import asyncio
import multiprocessing
import os
import random
import socket
import ssl
import struct
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, UNIT, Appliance, Checks, free_port, wait_until  # noqa: E402
from modbus_tls import client_context, make_pki, tls_section  # noqa: E402

HANDSHAKE_TIMEOUT_S = 3.0
MAX_CLIENTS = 16
PER_ADDRESS = 4
LEGIT = "127.0.0.2"
GARBAGE, TRUNCATED, SLOW = "127.0.0.3", "127.0.0.4", "127.0.0.5"
CROWD = ["127.0.0.6", "127.0.0.7", "127.0.0.8", "127.0.0.9"]
WRONG_CA = "127.0.0.10"
FINAL = "127.0.0.11"
STALLED = "127.0.0.12"
ATTACKERS = [GARBAGE, TRUNCATED, SLOW, *CROWD, WRONG_CA]


# ---- raw Modbus frames ----
def fc3(tid, address=0, count=10):
    return struct.pack(">HHHBBHH", tid & 0xFFFF, 0, 6, UNIT, 0x03, address, count)


def fc4(tid, address, count):
    return struct.pack(">HHHBBHH", tid & 0xFFFF, 0, 6, UNIT, 0x04, address, count)


def recv_exact(s, n):
    data = b""
    while len(data) < n:
        chunk = s.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed by the appliance")
        data += chunk
    return data


def answer(s):
    """One whole answer: (function code, payload)."""
    head = recv_exact(s, 7)
    body = recv_exact(s, struct.unpack(">H", head[4:6])[0] - 1)
    return body[0], body[1:]


# ---- the legitimate HMI, in its own process so the attackers' threads cannot delay it ----
def hmi(port, pki, stop, results, limit_s=90.0):
    """FC3 of 10 registers every 100 ms from LEGIT on one TLS connection, reconnecting when dropped,
    until `stop` is set (at most `limit_s`); puts [(start, answered, seconds, modbus_clients or None,
    error)] on `results`."""
    ctx = client_context(pki, pki, "hmi")
    polls, conn, tid = [], None, 0
    end = time.monotonic() + limit_s
    while time.monotonic() < end and not stop.is_set():
        t0 = time.monotonic()
        tid += 1
        ok, clients, error = False, None, ""
        try:
            if conn is None:
                raw = socket.create_connection((HOST, port), timeout=2.0, source_address=(LEGIT, 0))
                raw.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                conn = ctx.wrap_socket(raw, server_hostname="localhost")
            conn.sendall(fc3(tid))
            fc, payload = answer(conn)
            took = time.monotonic() - t0
            ok = fc == 0x03 and payload[0] == 20
            conn.sendall(fc4(tid, 126, 1))  # modbus_clients: not timed, the appliance's own count
            fc, payload = answer(conn)
            clients = struct.unpack(">H", payload[1:3])[0] if fc == 0x04 else None
        except (OSError, ssl.SSLError) as e:
            took, error = time.monotonic() - t0, f"{type(e).__name__}: {e}"
            if conn is not None:
                conn.close()
            conn = None
        polls.append((t0, ok, took, clients, error))
        time.sleep(max(0.0, 0.1 - (time.monotonic() - t0)))  # stays, the stimulus: an HMI's poll period
    if conn is not None:
        conn.close()
    results.put(polls)


# ---- the appliance's side of the connections ----
def held_by_server(port):
    """{peer address: connections} the appliance holds on `port` and has not closed (ESTABLISHED or
    CLOSE_WAIT rows whose local port is `port`; a connection still in the accept queue counts)."""
    counts = {}
    with open("/proc/net/tcp") as f:
        next(f)
        for line in f:
            fields = line.split()
            local, remote, state = fields[1], fields[2], fields[3]
            if int(local.split(":")[1], 16) != port or state not in ("01", "08"):
                continue
            ip = socket.inet_ntoa(struct.pack("<I", int(remote.split(":")[0], 16)))
            counts[ip] = counts.get(ip, 0) + 1
    return counts


def client_hello():
    """A real ClientHello record (TLS 1.3 and 1.2 offered), as Python's ssl sends it."""
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    ctx.check_hostname = False
    ctx.verify_mode = ssl.CERT_NONE
    incoming, outgoing = ssl.MemoryBIO(), ssl.MemoryBIO()
    obj = ctx.wrap_bio(incoming, outgoing, server_hostname="localhost")
    try:
        obj.do_handshake()
    except ssl.SSLWantReadError:
        pass
    return outgoing.read()


# ---- attackers (asyncio, one address each) ----
async def until_closed(reader):
    """Reads until the appliance closes; the loop time it did."""
    try:
        while await reader.read(65536):
            pass
    except (ConnectionError, OSError):
        pass
    return asyncio.get_running_loop().time()


async def hold(port, source, payload, every_s, limit_s, record, stop=None, reset=False):
    """Connects from `source`, sends `payload` (whole, or a byte every `every_s`), then waits until the
    appliance closes, at most `limit_s` from the connect (or until `stop` is set); with `reset`,
    resets the connection right after sending instead. Fills `record`: opened (loop time),
    closed_after (seconds from the connect, None while open; 0 after a reset), error."""
    loop = asyncio.get_running_loop()
    try:
        reader, writer = await asyncio.open_connection(HOST, port, local_addr=(source, 0))
    except OSError as e:
        record["error"] = str(e)
        return record
    t0 = record["opened"] = loop.time()
    record["closed_after"] = None
    if reset:
        writer.write(payload)
        await asyncio.sleep(0)  # the payload leaves before the reset
        writer.get_extra_info("socket").setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        writer.transport.abort()
        record["closed_after"] = 0.0
        return record
    closed = asyncio.ensure_future(until_closed(reader))
    waits = [closed] + ([asyncio.ensure_future(stop.wait())] if stop else [])
    try:
        if every_s is None:
            if payload:
                writer.write(payload)
        else:
            for i in range(len(payload)):
                if closed.done() or (stop and stop.is_set()) or loop.time() - t0 >= limit_s:
                    break
                writer.write(payload[i:i + 1])
                await asyncio.wait(waits, timeout=every_s, return_when=asyncio.FIRST_COMPLETED)  # the stimulus: a byte every every_s
        await asyncio.wait(waits, timeout=max(0.0, limit_s - (loop.time() - t0)), return_when=asyncio.FIRST_COMPLETED)
        if closed.done():
            record["closed_after"] = closed.result() - t0
    finally:
        for w in waits:
            w.cancel()
        writer.close()
    return record


def garbage_kinds(hello, rng):
    def flipped():
        b = bytearray(hello)
        for _ in range(rng.randint(1, 8)):
            b[rng.randrange(5, len(b))] ^= 1 << rng.randrange(8)
        return bytes(b)
    return [
        ("noise", lambda: rng.randbytes(rng.randint(5, 64))),
        ("16 KiB of noise", lambda: rng.randbytes(16384)),
        ("an HTTP request", lambda: b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"),
        ("a plain Modbus frame", lambda: fc3(1)),
        ("a record announcing 65535 bytes", lambda: b"\x16\x03\x01\xff\xff" + rng.randbytes(64)),
        ("an SSLv2-style hello", lambda: b"\x80\x2e\x01\x00\x02" + rng.randbytes(45)),
        ("an alert first", lambda: b"\x15\x03\x03\x00\x02\x02\x28"),
        ("noise, then a ClientHello", lambda: rng.randbytes(rng.randint(5, 64)) + hello),
        ("a ClientHello with bytes flipped", flipped),
        ("a ClientHello, then noise", lambda: hello + rng.randbytes(200)),
        ("3 bytes", lambda: b"\x16\x03\x01"),
        ("nothing", lambda: b""),
        ("a ClientHello, then a reset", lambda: hello),  # gone while the appliance answers it
    ]


async def garbage(port, hello, seconds, check):
    rng = random.Random(11)
    kinds = garbage_kinds(hello, rng)
    limit = HANDSHAKE_TIMEOUT_S + 2.0
    tasks, n = [], 0
    end = asyncio.get_running_loop().time() + seconds
    while asyncio.get_running_loop().time() < end:
        name, make = kinds[n % len(kinds)]
        reset = name.endswith("then a reset")
        tasks.append((name, asyncio.ensure_future(hold(port, GARBAGE, make(), None, limit, {}, reset=reset))))
        n += 1
        await asyncio.sleep(0.025)  # the stimulus: 40 connects a second
    worst, unclosed = {}, []
    for name, t in tasks:
        r = await t
        after = r.get("closed_after")
        if after is None:
            unclosed.append((name, r.get("error", "still open")))
        else:
            worst[name] = max(worst.get(name, 0.0), after)
    check(not unclosed, f"garbage: {len(tasks)} connections, each closed by the appliance "
                        f"(not closed within {limit:.0f} s: {unclosed[:5]})")
    slowest = max(worst.values(), default=0.0)
    check(slowest <= HANDSHAKE_TIMEOUT_S + 1.0,
          f"garbage: closed within handshake_timeout_s + 1 s; the slowest of each kind: "
          + ", ".join(f"{k} {v:.2f} s" for k, v in worst.items() if not k.endswith("then a reset")))


async def deadlines(port, hello, check):
    """Half a ClientHello then silence (4), a ClientHello a byte every 500 ms (4): each closed
    handshake_timeout_s after its connect."""
    limit = HANDSHAKE_TIMEOUT_S + 3.0
    truncated = [hold(port, TRUNCATED, hello[:len(hello) // 2], None, limit, {}) for _ in range(4)]
    slow = [hold(port, SLOW, hello, 0.5, limit, {}) for _ in range(4)]
    records = await asyncio.gather(*truncated, *slow)
    for what, rs in (("half a ClientHello, then silence", records[:4]), ("a ClientHello a byte every 500 ms", records[4:])):
        times = [r.get("closed_after") for r in rs]
        ok = all(t is not None and HANDSHAKE_TIMEOUT_S - 0.1 <= t <= HANDSHAKE_TIMEOUT_S + 1.0 for t in times)
        check(ok, f"{what}: closed {HANDSHAKE_TIMEOUT_S:.0f} s (handshake_timeout_s) after the connect: "
                  + ", ".join("open" if t is None else f"{t:.2f} s" for t in times))


def accept_queue(port):
    """The connections waiting in the listener's accept queue (its LISTEN row's rx_queue)."""
    with open("/proc/net/tcp") as f:
        next(f)
        for line in f:
            fields = line.split()
            if int(fields[1].split(":")[1], 16) == port and fields[3] == "0A":
                return int(fields[4].split(":")[1], 16)
    return 0


async def settled(port, records):
    """Waits (at most 3 s) until each of `records` has connected (or failed), the appliance has
    accepted every connection, and its side of the port stayed the same for 50 ms; that side."""
    loop = asyncio.get_running_loop()
    end = loop.time() + 3.0
    while loop.time() < end and not all("opened" in r or "error" in r for r in records):
        await asyncio.sleep(0.01)
    last = None
    while loop.time() < end:
        now = held_by_server(port) if accept_queue(port) == 0 else None
        if now is not None and now == last:
            return now
        last = now
        await asyncio.sleep(0.05)
    return held_by_server(port)


async def open_slow(port, hello, source, n, stop, tasks):
    """`n` slow handshakes from `source`, started at once (their tasks appended to `tasks`): the
    attackers' connections the appliance holds once it has dealt with them, all it holds, and the
    batch's records."""
    batch = [{"source": source} for _ in range(n)]
    tasks += [asyncio.ensure_future(hold(port, source, hello, 0.5, 60.0, r, stop)) for r in batch]
    held = await settled(port, batch)
    return {a: held.get(a, 0) for a in CROWD}, held, batch


async def at_the_cap(port, hello, check):
    """Slow handshakes filling max_clients and the per-address shares, all judged within the first
    connections' handshake_timeout_s."""
    wait_until(lambda: all(held_by_server(port).get(a, 0) == 0 for a in ATTACKERS), 5.0, 0.05)
    loop = asyncio.get_running_loop()
    stop, tasks = asyncio.Event(), []
    t0 = loop.time()
    for source in CROWD[:3]:
        filled, held, _ = await open_slow(port, hello, source, 5, stop, tasks)
    check(sum(held.values()) == MAX_CLIENTS and all(filled[a] == 5 for a in CROWD[:3]),
          f"slow handshakes fill the slots: .6, .7, .8 hold 5 each, {MAX_CLIENTS} with the HMI ({held})")
    after, held, batch = await open_slow(port, hello, CROWD[3], 8, stop, tasks)
    refused_at_once = sum(1 for r in batch if r.get("closed_after") is not None)
    check(after[CROWD[3]] == PER_ADDRESS and sum(held.values()) == MAX_CLIENTS and held.get(LEGIT) == 1,
          f"the server full, a newcomer address opening 8 holds its share ({PER_ADDRESS}), {refused_at_once} of its "
          f"connects closed at once, the HMI kept: {held}")
    biggest = max(CROWD[:3], key=lambda a: after[a])
    again, held, _ = await open_slow(port, hello, biggest, 4, stop, tasks)
    check(again == after and held.get(LEGIT) == 1,
          f"{biggest} (holding {after[biggest]}, at least its share) opens 4 more: it gains nothing, nobody else "
          f"loses: {after} -> {again}")
    took = loop.time() - t0
    check(took < HANDSHAKE_TIMEOUT_S - 0.3, f"... all judged {took:.2f} s after the first of them connected, before "
                                            "any handshake deadline (a machine too slow for this row fails it)")
    stop.set()
    await asyncio.gather(*tasks)


async def crowd(port, hello, seconds):
    """8 slow handshakes per address, each reconnecting 100 ms after it is closed; samples the
    appliance's side of the port every 250 ms (when its accept queue is empty). Returns (connects,
    samples)."""
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    connects = [0]

    async def slot(source):
        while loop.time() < end:
            connects[0] += 1
            await hold(port, source, hello, 0.5, end - loop.time(), {})
            await asyncio.sleep(0.1)  # the stimulus: an attacker reconnecting

    tasks = [asyncio.ensure_future(slot(a)) for a in CROWD for _ in range(8)]
    samples = []
    while loop.time() < end:
        await asyncio.sleep(0.25)
        if accept_queue(port) == 0:  # connects not yet accepted are no slots of the appliance's
            samples.append(held_by_server(port))
    await asyncio.gather(*tasks)
    return connects[0], samples


def wrong_ca(port, pki, other, n):
    """`n` connects from WRONG_CA with another CA's certificate: how many were refused."""
    ctx = client_context(pki, other, "hmi")
    refused = 0
    for i in range(n):
        try:
            with socket.create_connection((HOST, port), timeout=3, source_address=(WRONG_CA, 0)) as raw:
                with ctx.wrap_socket(raw, server_hostname="localhost") as s:
                    s.sendall(fc3(i))
                    refused += s.recv(64) == b""
        except (ssl.SSLError, ConnectionError, socket.timeout):
            refused += 1
    return refused


def renegotiation(port, pki, check):
    """s_client over TLS 1.2: a raw FC3 read, then "R" (renegotiate): refused, and the connection ends."""
    cmd = ["openssl", "s_client", "-tls1_2", "-connect", f"{HOST}:{port}", "-servername", "localhost",
           "-CAfile", os.path.join(pki, "ca.pem"), "-cert", os.path.join(pki, "hmi.pem"), "-key", os.path.join(pki, "hmi.key")]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out, err = bytearray(), bytearray()

    def pump(stream, into):
        for chunk in iter(lambda: stream.read1(4096), b""):
            into.extend(chunk)
    pumps = [threading.Thread(target=pump, args=(proc.stdout, out), daemon=True),
             threading.Thread(target=pump, args=(proc.stderr, err), daemon=True)]
    for p in pumps:
        p.start()
    try:
        wait_until(lambda: b"Verify return code" in out or proc.poll() is not None, 10.0, 0.05)
        expected = bytes.fromhex("0101000000170103") + bytes([20])  # the answer's head: tid 0x0101, 20 bytes of data
        proc.stdin.write(fc3(0x0101))
        proc.stdin.flush()
        read = wait_until(lambda: expected in out, 5.0, 0.05)
        proc.stdin.write(b"R\n")  # s_client's command: renegotiate
        proc.stdin.flush()
        try:
            proc.wait(timeout=5)
            ended = True
        except subprocess.TimeoutExpired:
            ended = False
    except OSError:
        ended = proc.poll() is not None
        read = False
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=5)
        for p in pumps:
            p.join(timeout=5)
    text = err.decode(errors="replace")
    check(b"Protocol  : TLSv1.2" in out and read, f"s_client -tls1_2: connected and its FC3 answered ({bool(read)})")
    check("RENEGOTIATING" in text and "no renegotiation" in text,
          f"renegotiation asked for and refused (no_renegotiation): {text.strip().splitlines()[-2:]}")
    check(ended, "... and the connection ended (s_client exited within 5 s)")
    gone = wait_until(lambda: held_by_server(port).get("127.0.0.1", 0) == 0, 3.0, 0.05)
    check(gone, "... and the appliance holds no connection from it")


def cpu_seconds(pid):
    """The user + system CPU time of process `pid` so far."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def stalled_record(port, pki, pid, check):
    """A viewer that, after its handshake and a read, sends 3 bytes of a record header and stalls: the
    appliance waits for the rest on the socket, it does not spin (its CPU time over 2 s)."""
    ctx = client_context(pki, pki, "view")
    with socket.create_connection((HOST, port), timeout=3, source_address=(STALLED, 0)) as raw:
        with ctx.wrap_socket(raw, server_hostname="localhost") as s:
            s.sendall(fc3(1))
            answer(s)
            os.write(s.fileno(), b"\x17\x03\x03")  # under the TLS layer: a record's first bytes
            before = cpu_seconds(pid)
            time.sleep(2.0)  # stays, the stimulus: the record stays incomplete this long
            used = cpu_seconds(pid) - before
    check(used < 0.5, f"a certified client stalled mid-record for 2 s: the appliance used {used:.2f} s of CPU (no spinning)")


def still_answers(app, port, pki, check):
    ctx = client_context(pki, pki, "view")
    try:
        with socket.create_connection((HOST, port), timeout=3, source_address=(FINAL, 0)) as raw:
            with ctx.wrap_socket(raw, server_hostname="localhost") as s:
                s.sendall(fc3(7))
                fc, payload = answer(s)
        check(fc == 3 and payload[0] == 20, "after it all, a fresh TLS client is answered")
    except (OSError, ssl.SSLError) as e:
        check(False, f"after it all, a fresh TLS client is answered: {e}")
    try:
        with socket.create_connection((HOST, app.port), timeout=3) as s:
            s.sendall(fc3(8))
            fc, payload = answer(s)
        check(fc == 3 and payload[0] == 20, "... and a plain Modbus client")
    except OSError as e:
        check(False, f"... and a plain Modbus client: {e}")


async def attacks(port, pki, other, pid, check):
    hello = client_hello()
    await garbage(port, hello, 3.0, check)
    await deadlines(port, hello, check)
    await at_the_cap(port, hello, check)
    connects, samples = await crowd(port, hello, 8.0)
    over = sum(1 for s in samples if any(s.get(a, 0) > PER_ADDRESS for a in CROWD))
    most = max((max(s.get(a, 0) for a in CROWD) for s in samples), default=0)
    print(f"crowd: {connects} slow handshakes from {len(CROWD)} addresses in 8 s; the appliance's side sampled "
          f"{len(samples)} times: at most {max((sum(s.values()) for s in samples), default=0)} connections, an address "
          f"at most {most}, above its share in {over} samples", flush=True)
    n = 20
    refused = await asyncio.to_thread(wrong_ca, port, pki, other, n)
    check(refused == n, f"a certificate of another CA: {refused} of {n} connects refused")
    await asyncio.to_thread(renegotiation, port, pki, check)
    await asyncio.to_thread(stalled_record, port, pki, pid, check)


def main():
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    reg_map = os.path.join(src, "registers", "epa.csv")
    check = Checks()
    root = Appliance(epa, reg_map, start=False)  # a temporary folder for the certificates
    pki, other = make_pki(epa, root.dir, [("hmi", "operator"), ("view", "viewer")])
    port = free_port()
    app = Appliance(epa, reg_map, extra_config=tls_section(pki, port, f"handshake_timeout_s = {HANDSHAKE_TIMEOUT_S}\n"),
                    modbus_extra=f"max_clients = {MAX_CLIENTS}\nmax_clients_per_address = {PER_ADDRESS}\n")
    app.client.close()  # its slot is not needed: the checks count the slots
    app.client = None
    results, stop_hmi = multiprocessing.Queue(), multiprocessing.Event()
    legit = None
    status = None
    polls = []
    try:
        legit = multiprocessing.Process(target=hmi, args=(port, pki, stop_hmi, results), daemon=True)
        legit.start()
        wait_until(lambda: held_by_server(port).get(LEGIT, 0) == 1, 5.0, 0.05)
        t0 = time.monotonic()
        asyncio.run(attacks(port, pki, other, app.proc.pid, check))
        print(f"attacks took {time.monotonic() - t0:.1f} s", flush=True)
        stop_hmi.set()
        polls = results.get(timeout=10)
        still_answers(app, port, pki, check)
        check(app.proc.poll() is None, "the appliance is still running")
    finally:
        stop_hmi.set()
        if legit is not None:
            legit.join(timeout=5)
            if legit.is_alive():
                legit.terminate()
                legit.join(timeout=5)
        status = app.stop()
    check(status == 0, f"SIGTERM: the appliance exits with 0 ({status})")
    served = sum(1 for _, ok, took, _, _ in polls if ok and took <= 1.0)
    errors = sorted({e for *_, e in polls if e})
    slowest = max((took for _, _, took, _, _ in polls), default=0.0)
    check(polls and served >= 0.95 * len(polls),
          f"the HMI's polls answered within 1 s: {served} of {len(polls)} (bound 95 %; slowest {slowest:.3f} s; "
          f"errors {errors[:3]})")
    counts = [c for *_, c, _ in polls if c is not None]
    check(counts and max(counts) <= MAX_CLIENTS, f"the appliance never counts more than max_clients ({MAX_CLIENTS}) "
                                                  f"clients: at most {max(counts, default=None)}")

    log = open(app.log_path).read().splitlines()
    for a in ATTACKERS:
        lines = [line for line in log if f"{a} refused in the TLS handshake" in line]
        check(len(lines) == 1, f"{a}: its refusals logged once ({len(lines)} lines{': ' + lines[0] if lines else ''})")
    check(len(log) <= 80, f"the log stays short: {len(log)} lines")
    app.remove()
    root.remove()
    print(f"tls abuse: {len(check.failures)} failed" if check.failures else "tls abuse: every check passed")
    return 1 if check.failures else 0


if __name__ == "__main__":
    sys.exit(main())
