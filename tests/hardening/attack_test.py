#!/usr/bin/env python3
"""Hostile clients, as an attacker on the plant network would try them: raw sockets and
hand-built Modbus frames (nothing of the project's Modbus code), against `epa serve` on loopback
with a key and the shipped limits. The attacks this release answers, one row each:

  brute force   50 wrong 64-bit keys pipelined on one connection, then the right key from the same
                address: the right key is refused (04, locked out), `locked` stays 1,
                `unlock_failures` >= 50, the log names the address
  unlock scope  a second connection that never sent the key cannot write m_r (04) while the
                first one can
  idle + slow   16 idle and 16 one-byte-a-second connections held open (max_clients 16): a
                client's polls are served within 1 s at least 95 % of the time
  300 idle      300 idle connections opened at once: a client is still served
  burst         300 connects fired at once (Modbus), 600 silent ones (HTTP, three times: more than
                its 512 workers): a fresh client's read right after is answered within 0.5 s (a listen
                queue too short drops its SYN: 1 s retry; a silent connection holding a worker: 2 s)
  bad config    idle_timeout_s = 1e300, unlock_timeout_s = 1e300, [recorder] buffer_s = 1e12, a
                4-digit unlock key: `epa serve` refuses to start, naming file, line and key
  spreadsheet   the shipped register map saved with a byte-order mark and CRLF: it starts
  slow HTTP     200 connections sending one header byte a second: /api/status answered within
                1 s at least 95 % of the time
  head deadline a request head sent a byte every 0.3 s: answered 408 and closed about 2 s after
                its first byte (each byte resets httplib's own read timeout; this is ours)
  big heads     2,000 header lines, 1 MB of headers: refused (431); Content-Length 10^12:
                413 at once
  token guess   wrong tokens: after 5 the address gets 429 without a look at the token, the
                log names it

    attack_test.py <epa binary> <source dir> [HOLD_SECONDS=8]

HOLD_SECONDS is how long the idle and slow connections are held while a client polls
(bench/attack.sh runs it for 60 s: the longer version).
Loopback only, every loop bounded; the appliances are stopped by their PID. Exit 0 when every row
holds, 1 otherwise (each failure says what was expected and what came back).
"""
import os
import select
import socket
import struct
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, UNIT, UNLOCK_ADDRESS, UNLOCK_KEY, Appliance, f32_words, key_words, wait_until  # noqa: E402

M_R = 20
failures = []


def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what, flush=True)
    if not ok:
        failures.append(what)


# ---- raw Modbus TCP: frames built here, answers parsed here ----
def fc16(tid, address, words):
    pdu = struct.pack(">BHHB", 0x10, address, len(words), 2 * len(words)) + b"".join(struct.pack(">H", w) for w in words)
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, UNIT) + pdu


def fc4(tid, address, count):
    return struct.pack(">HHHBBHH", tid, 0, 6, UNIT, 0x04, address, count)


def read_answer(s):
    """One whole answer: (function code, payload bytes)."""
    head = b""
    while len(head) < 7:
        chunk = s.recv(7 - len(head))
        if not chunk:
            raise ConnectionError("closed by the appliance")
        head += chunk
    length = struct.unpack(">H", head[4:6])[0] - 1
    body = b""
    while len(body) < length:
        chunk = s.recv(length - len(body))
        if not chunk:
            raise ConnectionError("closed by the appliance")
        body += chunk
    return body[0], body[1:]


def connect(port, timeout=2.0):
    s = socket.create_connection((HOST, port), timeout=timeout)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def exception_of(answer):
    fc, payload = answer
    return payload[0] if fc & 0x80 else 0


def input_u32(s, address):
    s.sendall(fc4(1, address, 2))
    fc, payload = read_answer(s)
    return struct.unpack(">I", payload[1:5])[0]


def clients_seen_by(s):
    """modbus_clients (input register 126): the connected clients the appliance counts."""
    s.sendall(fc4(9, 126, 1))
    fc, payload = read_answer(s)
    return struct.unpack(">H", payload[1:3])[0]


def discrete_locked(s):
    s.sendall(struct.pack(">HHHBBHH", 2, 0, 6, UNIT, 0x02, 3, 1))  # discrete input 3: locked
    fc, payload = read_answer(s)
    return payload[1] & 1


# ---- the rows ----
def brute_force(app):
    # From 127.0.0.2, so the back-off it earns does not touch the other rows' 127.0.0.1.
    s = socket.create_connection((HOST, app.port), timeout=2, source_address=("127.0.0.2", 0))
    key = int(UNLOCK_KEY, 16)
    frames = b"".join(fc16(i, UNLOCK_ADDRESS, key_words("%016x" % (key ^ (i << 20)))) for i in range(1, 51))
    s.sendall(frames)  # pipelined, as a brute force would
    codes = [exception_of(read_answer(s)) for _ in range(50)]
    check(codes[:5] == [3] * 5 and set(codes[5:]) == {4},
          f"50 wrong keys: the first 5 looked at (03), the rest refused unseen (04): {codes}")
    s.sendall(fc16(99, UNLOCK_ADDRESS, key_words()))
    check(exception_of(read_answer(s)) == 4, "the right key during the back-off is refused (04)")
    check(discrete_locked(s) == 1, "locked stays 1")
    failures_count = input_u32(s, 132)
    check(failures_count >= 50, f"unlock_failures >= 50 ({failures_count})")
    s.close()
    wait_until(lambda: "refused for 10 s" in app.log_text(), 5.0, 0.05)  # the log line, bounded
    log = app.log_text()
    check("127.0.0.2:" in log and "wrong unlock key" in log and "refused for 10 s" in log,
          "the log names the address and the lock-out")


def unlock_scope(app):
    a, b = connect(app.port), connect(app.port)
    a.sendall(fc16(1, UNLOCK_ADDRESS, key_words()))
    check(exception_of(read_answer(a)) == 0, "the key unlocks its own connection")
    b.sendall(fc16(2, M_R, f32_words(1.8, "ABCD")))
    check(exception_of(read_answer(b)) == 4, "a second connection that never sent the key cannot write m_r (04)")
    a.sendall(fc16(3, M_R, f32_words(1.8, "ABCD")))
    check(exception_of(read_answer(a)) == 0, "the unlocked connection can")
    a.close()
    wait_until(lambda: clients_seen_by(b) == 1, 3.0, 0.02)  # the appliance has dropped a
    c = connect(app.port)
    c.sendall(fc16(4, M_R, f32_words(1.9, "ABCD")))
    check(exception_of(read_answer(c)) == 4, "after the unlocked connection closed, a new one is locked")
    c.close()
    b.close()


def poll_while_held(app, idle, slow, seconds):
    """Opens `idle` silent and `slow` one-byte-a-second connections, then polls with a client that
    reconnects when it is dropped; the share of polls answered within 1 s."""
    held = [connect(app.port) for _ in range(idle)]
    stop = threading.Event()

    def dribble():
        frame = fc4(7, 0, 2)
        while not stop.is_set():
            try:
                s = connect(app.port)
                for i in range(len(frame)):
                    if stop.wait(1.0):
                        break
                    s.sendall(frame[i:i + 1])
                s.close()
            except OSError:
                stop.wait(0.1)

    slow_threads = [threading.Thread(target=dribble, daemon=True) for _ in range(slow)]
    for t in slow_threads:
        t.start()
    time.sleep(1.5)  # stays, the stimulus: the slow ones are mid-frame now
    served = total = 0
    client = None
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        total += 1
        t0 = time.monotonic()
        try:
            if client is None:
                client = connect(app.port, timeout=1.0)
            client.sendall(fc4(total & 0xFFFF, 0, 2))
            fc, _ = read_answer(client)
            if fc == 0x04 and time.monotonic() - t0 <= 1.0:
                served += 1
        except OSError:
            if client:
                client.close()
            client = None
        time.sleep(max(0.0, 0.1 - (time.monotonic() - t0)))
    stop.set()
    for t in slow_threads:
        t.join(timeout=3)
    for s in held:
        s.close()
    if client:
        client.close()
    return served, total


def connect_burst(port, connects=300, sources=None):
    """Fires `connects` connects at once without a byte sent (a reconnect storm, a flood) and
    leaves them open; the sockets, to be closed by the caller. `sources`: the addresses they come
    from, in turn (HTTP caps the connections of one address)."""
    burst = []
    for i in range(connects):
        s = socket.socket()
        s.setblocking(False)
        if sources:
            s.bind((sources[i % len(sources)], 0))
        s.connect_ex((HOST, port))
        burst.append(s)
    return burst


def modbus_poll_after_burst(port):
    """The seconds a fresh client takes to connect and read two input registers right after a
    burst of connects (Modbus); None when it got no answer."""
    burst = connect_burst(port)
    try:
        t0 = time.monotonic()
        with connect(port, timeout=3.0) as s:
            s.sendall(fc4(9, 0, 2))
            answer = read_answer(s)
        return time.monotonic() - t0 if exception_of(answer) == 0 else None
    except OSError:
        return None
    finally:
        for b in burst:
            b.close()


def http_poll_after_burst(port):
    """The status line and seconds of /api/status right after a burst of 600 silent connects (HTTP:
    more than the 512 workers, so each silent connection must not hold one)."""
    burst = connect_burst(port, 600, [f"127.0.0.{10 + i}" for i in range(40)])  # 15 an address: under its cap of 32
    try:
        return http_raw(port, b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", timeout=3.0)
    except OSError as e:
        return f"no connection: {e}", 3.0
    finally:
        for b in burst:
            b.close()


def http_raw(port, request, timeout=5.0):
    """The status line of the answer to a raw request, and the seconds it took."""
    t0 = time.monotonic()
    with socket.create_connection((HOST, port), timeout=timeout) as s:
        try:
            s.sendall(request)
        except OSError:
            pass  # the server may close before it has read everything: what it answered counts
        line = status_line(s)
    return line, time.monotonic() - t0


def status_line(s, until_closed=False):
    """The first line of what the server sends on `s` (reading on to its close if asked)."""
    data = b""
    try:
        while until_closed or b"\r\n" not in data:
            chunk = s.recv(4096)
            if not chunk:
                break
            data += chunk
    except OSError:
        pass
    return data.split(b"\r\n")[0].decode(errors="replace")


def slow_http(app, connections, seconds):
    stop = threading.Event()
    head = b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 100 + b"\r\n\r\n"

    def dribble(source):
        while not stop.is_set():
            try:
                with socket.create_connection((HOST, app.web_port), timeout=2, source_address=(source, 0)) as s:
                    for i in range(len(head)):
                        if stop.wait(1.0):
                            return
                        s.sendall(head[i:i + 1])
            except OSError:
                stop.wait(0.1)

    # From 20 addresses other than the poller's, each under the HTTP per-address cap of 32.
    threads = [threading.Thread(target=dribble, args=(f"127.0.0.{10 + i % 20}",), daemon=True) for i in range(connections)]
    for t in threads:
        t.start()
    time.sleep(2.0)  # stays, the stimulus: the crowd connects and dribbles before the polls
    served = total = 0
    slowest_s, unexpected = 0.0, set()
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        total += 1
        try:
            line, took = http_raw(app.web_port, b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", timeout=2.0)
        except OSError as e:
            line, took = f"no connection: {e}", 2.0
        slowest_s = max(slowest_s, took)
        if line.startswith("HTTP/1.1 200") and took <= 1.0:
            served += 1
        elif not line.startswith("HTTP/1.1 200"):
            unexpected.add(line)
        time.sleep(0.1)
    stop.set()
    for t in threads:
        t.join(timeout=3)
    return served, total, slowest_s, sorted(unexpected)


def dribbled_head(port):
    """Sends a request head a byte every 0.3 s until the server answers or closes: its status line
    and the seconds from the first byte to the end of the connection."""
    head = b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 200 + b"\r\n\r\n"
    with socket.create_connection((HOST, port), timeout=10) as s:
        t0 = time.monotonic()
        for i in range(len(head)):  # 75 s at most: the deadline must end it long before
            try:
                s.sendall(head[i:i + 1])
            except OSError:
                break
            r, _, _ = select.select([s], [], [], 0.3)
            if r:
                break
        line = status_line(s, until_closed=True)
        return line, time.monotonic() - t0


def http_rows(app, hold_s):
    served, total, slowest_s, unexpected = slow_http(app, 200, hold_s)
    check(total > 0 and served >= 0.95 * total,
          f"200 slow HTTP connections: {served} of {total} /api/status answered within 1 s "
          f"(slowest {slowest_s:.2f} s{', other answers: ' + repr(unexpected) if unexpected else ''})")
    line, took = max((http_poll_after_burst(app.web_port) for _ in range(3)), key=lambda r: (not r[0].startswith("HTTP/1.1 200"), r[1]))
    check(line.startswith("HTTP/1.1 200") and took <= 0.5,
          f"600 silent connects at once, then /api/status, three times: answered within 0.5 s: the worst {line!r} after {took:.2f} s")
    line, took = dribbled_head(app.web_port)
    check(line.startswith("HTTP/1.1 408") and 1.5 <= took <= 3.5,
          f"a head dribbled a byte every 0.3 s: 408 and closed 2 s after its first byte: {line!r} after {took:.1f} s")
    lines = b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n" + b"".join(b"X-%d: y\r\n" % i for i in range(2000)) + b"\r\n"
    line, _ = http_raw(app.web_port, lines)
    check(line.startswith("HTTP/1.1 4"), f"2,000 header lines refused: {line}")
    megabyte = b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n" + b"".join(b"X-%d: %s\r\n" % (i, b"a" * 1000) for i in range(1000)) + b"\r\n"
    line, _ = http_raw(app.web_port, megabyte)
    check(line.startswith("HTTP/1.1 4"), f"1 MB of headers refused: {line}")
    line, took = http_raw(app.web_port, b"POST /api/setpoint HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 1000000000000\r\n\r\n{")
    check(line.startswith("HTTP/1.1 413") and took < 1.0, f"Content-Length 10^12: {line} after {took:.2f} s")
    codes = []
    for i in range(8):
        body = b'{"setpoint_mm": 10}'
        req = (b"POST /api/setpoint HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer guess-%d-xxxxxxxxxxxx\r\n"
               b"Content-Type: application/json\r\nContent-Length: %d\r\nConnection: close\r\n\r\n%s" % (i, len(body), body))
        codes.append(http_raw(app.web_port, req)[0][9:12])
    check(codes[:5] == ["401"] * 5 and set(codes[5:]) == {"429"}, f"token guessing: 401 five times, then 429: {codes}")
    wait_until(lambda: "wrong tokens from 127.0.0.1" in app.log_text(), 5.0, 0.05)  # the log line, bounded
    check("wrong tokens from 127.0.0.1" in app.log_text(), "the log names the guessing address")


def refused_config(epa, src, tmp, edit, expect):
    """`epa serve` with the shipped configuration plus one edit: it must refuse to start."""
    base = open(os.path.join(src, "config", "epa.toml")).read()
    base = base.replace('"../registers/epa.csv"', f'"{src}/registers/epa.csv"').replace('"../web"', f'"{src}/web"')
    base = base.replace("port = 502", "port = 0").replace("port = 8080", "port = 0")
    path = os.path.join(tmp, "bad.toml")
    with open(path, "w") as f:
        f.write(edit(base))
    r = subprocess.run([epa, "serve", "--config", path, "--db", os.path.join(tmp, "bad.db"), "--duration", "1"],
                       capture_output=True, text=True, timeout=30)
    check(r.returncode != 0 and all(e in r.stderr for e in expect),
          f"refused to start naming {expect}: exit {r.returncode}, {r.stderr.strip()}")


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir> [HOLD_SECONDS]")
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    hold_s = float(sys.argv[3]) if len(sys.argv) == 4 else 8.0
    reg_map = os.path.join(src, "registers", "epa.csv")

    app = Appliance(epa, reg_map, "", modbus_extra="max_clients = 16\n", web_static_dir=os.path.join(src, "web"),
                    web_extra='token = "90t7oIsgbHRGOIHHO5qHvUCU"\n')
    try:
        brute_force(app)
        unlock_scope(app)
        served, total = poll_while_held(app, idle=16, slow=16, seconds=hold_s)
        check(total > 0 and served >= 0.95 * total, f"16 idle + 16 slow connections: {served} of {total} polls served within 1 s")
        served, total = poll_while_held(app, idle=300, slow=0, seconds=min(hold_s, 5.0))
        check(total > 0 and served >= 0.95 * total, f"300 idle connections: {served} of {total} polls served within 1 s")
        took = modbus_poll_after_burst(app.port)
        check(took is not None and took <= 0.5, f"300 connects at once, then a Modbus read: answered within 0.5 s: {took}")
        http_rows(app, hold_s)
        check(app.proc.poll() is None, "the appliance is still running")
    finally:
        app.stop()
        tmp = app.dir
        for edit, expect in (
                (lambda t: t.replace("idle_timeout_s = 60.0", "idle_timeout_s = 1e300"), ["bad.toml:", "modbus.idle_timeout_s"]),
                (lambda t: t.replace("unlock_timeout_s = 60.0", "unlock_timeout_s = 1e300"), ["modbus.unlock_timeout_s"]),
                (lambda t: t.replace("buffer_s = 60.0", "buffer_s = 1e12"), ["recorder.buffer_s"]),
                (lambda t: t.replace('unlock_key = ""', 'unlock_key = "4321"'), ["modbus.unlock_key", "16 hex digits"]),
                (lambda t: t.replace('token = ""', 'token = "1"'), ["web.token", "16 characters"])):
            refused_config(epa, src, tmp, edit, expect)
        app.remove()

    # A map as a spreadsheet saves it: byte-order mark, CRLF.
    excel = Appliance(epa, reg_map, "", start=False)
    try:
        excel_map = os.path.join(excel.dir, "excel.csv")
        with open(reg_map, newline="") as f, open(excel_map, "w", newline="", encoding="utf-8-sig") as out:
            out.write(f.read().replace("\n", "\r\n"))
        text = open(excel.config).read().replace(reg_map, excel_map)
        open(excel.config, "w").write(text)
        try:
            excel.start()
            check(not excel.client.read_input_registers(0, 2, slave=UNIT).isError(), "a map with a BOM and CRLF is read")
        except Exception as e:  # noqa: BLE001 - any failure to start is the finding
            check(False, f"a map with a BOM and CRLF is read: {e}; {excel.log_text()[-500:]}")
    finally:
        excel.stop()
        excel.remove()

    print(f"attack: {len(failures)} of the rows failed" if failures else "attack: every row held")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
