#!/usr/bin/env python3
"""1,000 slow HTTP connections against `epa serve`, with raw sockets only (nothing of the project on
the client side), while the status page polls /api/status once a second:

  many addresses  1,000 connections from 100 loopback addresses (127.0.0.10-109, 10 each), each
                  sending its request head a byte every 0.5 s and reconnecting when it is cut
  one address     1,000 connections from 127.0.0.2 alone (the per-address cap closes all but 32 at
                  once; they reconnect a second later)

  slow readers    1,500 connections from 50 addresses (30 each, under the cap), each with a 4 KiB
                  receive buffer, pipelining 200 requests for /api/trend and never reading an
                  answer (workers once blocked writing to them: 0 % of polls at 3,000), reconnecting
                  a second after the appliance closes one

For each, two pollers from 127.0.0.1: one that opens a fresh connection per poll and one that keeps
its connection. Passes when each answers within 1 s for at least 95 % of its polls. It also checks
that the appliance raised its open-files soft limit (started here with 1024) and that refusals are
logged as a count, not a line each.

    http_crowd_test.py <epa binary> <source dir> [SECONDS_PER_CROWD=15]

Loopback only, every loop bounded; the appliance is stopped by its PID. Exit 0 when every check
holds, 1 otherwise.
"""
import errno
import multiprocessing
import os
import resource
import selectors
import socket
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import Appliance  # noqa: E402

CROWD = 1000
HEAD = b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 200 + b"\r\n\r\n"
failures = []


def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what, flush=True)
    if not ok:
        failures.append(what)


class SlowCrowd:
    """`CROWD` connections from `sources` (round robin), each sending HEAD a byte every 0.5 s, on one
    thread; a connection that is closed or refused is opened again after `reconnect_s`."""

    def __init__(self, port, sources, reconnect_s=1.0):
        self.port, self.sources, self.reconnect_s = port, sources, reconnect_s
        self.stop_flag = threading.Event()
        self.open_samples = []
        self.reconnects = 0
        self.refused = 0  # answered 503 (too many connections) at once
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _connect(self, i):
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setblocking(False)
        try:
            s.bind((self.sources[i % len(self.sources)], 0))
            s.connect_ex(("127.0.0.1", self.port))
        except OSError:
            s.close()
            return None
        return s

    def _run(self):
        slots = [None] * CROWD          # socket or None
        sent = [0] * CROWD              # bytes of HEAD sent on it
        retry_at = [0.0] * CROWD        # when a closed slot connects again
        sel = selectors.DefaultSelector()
        next_byte = time.monotonic()
        while not self.stop_flag.is_set():
            now = time.monotonic()
            for i in range(CROWD):
                if slots[i] is None and now >= retry_at[i]:
                    s = self._connect(i)
                    if s is not None:
                        slots[i], sent[i] = s, 0
                        sel.register(s, selectors.EVENT_READ, i)
                        self.reconnects += 1
                    else:
                        retry_at[i] = now + self.reconnect_s
            if now >= next_byte:  # one more byte on every open connection
                next_byte = now + 0.5
                for i, s in enumerate(slots):
                    if s is None:
                        continue
                    try:
                        if s.send(HEAD[sent[i] % len(HEAD):sent[i] % len(HEAD) + 1]) == 1:
                            sent[i] += 1
                    except OSError as e:
                        if e.errno not in (errno.EAGAIN, errno.ENOTCONN):
                            self._drop(sel, slots, retry_at, i, now)
                self.open_samples.append(sum(1 for s in slots if s is not None))
            for key, _ in sel.select(timeout=0.05):  # an answer (408, 503) or a close: the slot starts over
                i = key.data
                try:
                    data = slots[i].recv(4096)
                except OSError:
                    data = b""
                if data.startswith(b"HTTP/1.1 503"):
                    self.refused += 1
                if not data or b"\r\n\r\n" in data:
                    self._drop(sel, slots, retry_at, i, time.monotonic())
        for i, s in enumerate(slots):
            if s is not None:
                sel.unregister(s)
                s.close()

    def _drop(self, sel, slots, retry_at, i, now):
        sel.unregister(slots[i])
        slots[i].close()
        slots[i] = None
        retry_at[i] = now + self.reconnect_s

    def close(self):
        self.stop_flag.set()
        self.thread.join(timeout=10)


class SlowReaders:
    """`count` connections from `sources` that pipeline requests and never read; one is opened
    again a second after the appliance closes it. In a process of its own: a crowd that shares the
    pollers' interpreter would delay their polls itself."""

    REQUESTS = b"GET /api/trend HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n" * 200

    def __init__(self, port, sources, count):
        self.stop_flag = multiprocessing.Event()
        self.held = multiprocessing.Value("i", 0)
        self.connects = multiprocessing.Value("i", 0)
        self.process = multiprocessing.Process(target=SlowReaders._run, args=(port, sources, count, self.stop_flag, self.held,
                                                                               self.connects), daemon=True)
        self.process.start()

    @property
    def open_samples(self):
        return [self.held.value]

    @property
    def reconnects(self):
        return self.connects.value

    @staticmethod
    def _open(port, source):
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            s.bind((source, 0))
            s.settimeout(0.5)
            s.connect(("127.0.0.1", port))
            s.setblocking(False)
            try:
                s.send(SlowReaders.REQUESTS)
            except OSError:
                pass  # what the socket took is enough
            return s
        except OSError:
            s.close()
            return None

    @staticmethod
    def _run(port, sources, count, stop_flag, held, connects):
        slots = [None] * count
        retry_at = [0.0] * count
        while not stop_flag.is_set():
            now = time.monotonic()
            for i in range(count):
                s = slots[i]
                if s is not None:
                    try:  # closed by the appliance? (a peek, never a read of an answer)
                        if s.recv(1, socket.MSG_PEEK) == b"":
                            s.close()
                            slots[i], retry_at[i] = None, now + 1.0
                    except BlockingIOError:
                        pass
                    except OSError:
                        s.close()
                        slots[i], retry_at[i] = None, now + 1.0
                elif now >= retry_at[i]:
                    slots[i] = SlowReaders._open(port, sources[i % len(sources)])
                    connects.value += 1
                    if slots[i] is None:
                        retry_at[i] = now + 1.0
            held.value = sum(1 for s in slots if s is not None)
            stop_flag.wait(0.2)
        for s in slots:
            if s is not None:
                s.close()

    def close(self):
        self.stop_flag.set()
        self.process.join(timeout=20)


def read_answer(s, deadline):
    """One HTTP answer (head and Content-Length body) from `s`; the status line, or None."""
    data = b""
    while b"\r\n\r\n" not in data:
        s.settimeout(max(0.001, deadline - time.monotonic()))
        chunk = s.recv(4096)
        if not chunk:
            return None
        data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    length = 0
    for line in head.split(b"\r\n")[1:]:
        name, _, value = line.partition(b":")
        if name.strip().lower() == b"content-length":
            length = int(value.strip())
    while len(body) < length:
        s.settimeout(max(0.001, deadline - time.monotonic()))
        chunk = s.recv(4096)
        if not chunk:
            return None
        body += chunk
    return head.split(b"\r\n")[0].decode()


def poll(port, seconds, persistent, results):
    """Polls /api/status once a second from 127.0.0.1; appends (answered within 1 s, took_s)."""
    conn = None
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        t0 = time.monotonic()
        deadline = t0 + 1.0
        ok = False
        try:
            if conn is None:
                conn = socket.create_connection(("127.0.0.1", port), timeout=1.0, source_address=("127.0.0.1", 0))
            conn.sendall(b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n" +
                         (b"\r\n" if persistent else b"Connection: close\r\n\r\n"))
            status = read_answer(conn, deadline)
            ok = status == "HTTP/1.1 200 OK" and time.monotonic() <= deadline
        except OSError:
            ok = False
        if not ok or not persistent:
            if conn is not None:
                conn.close()
            conn = None
        results.append((ok, time.monotonic() - t0))
        time.sleep(max(0.0, 1.0 - (time.monotonic() - t0)))
    if conn is not None:
        conn.close()


def crowd_row(app, name, sources, seconds, readers=0):
    crowd = SlowReaders(app.web_port, sources, readers) if readers else SlowCrowd(app.web_port, sources)
    time.sleep(3.0 if readers else 2.0)  # the crowd connects
    fresh, kept = [], []
    pollers = [threading.Thread(target=poll, args=(app.web_port, seconds, False, fresh)),
               threading.Thread(target=poll, args=(app.web_port, seconds, True, kept))]
    for t in pollers:
        t.start()
    for t in pollers:
        t.join(timeout=seconds + 10)
    crowd.close()
    held = sorted(crowd.open_samples)[len(crowd.open_samples) // 2] if crowd.open_samples else 0
    for label, results in (("a fresh connection per poll", fresh), ("a kept connection", kept)):
        answered = sum(1 for ok, _ in results if ok)
        share = 100.0 * answered / max(1, len(results))
        worst = max((took for _, took in results), default=0.0)
        check(len(results) >= seconds - 2 and share >= 95.0,
              f"{name}: /api/status within 1 s, {label}: {answered}/{len(results)} = {share:.0f} % (>= 95 %), "
              f"slowest {worst:.3f} s; crowd: {held} connections open (median), {crowd.reconnects} connects")
    return held, getattr(crowd, "refused", 0)


def main():
    epa, src = sys.argv[1], sys.argv[2]
    seconds = int(sys.argv[3]) if len(sys.argv) > 3 else 15
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (min(1024, hard), hard))  # what a process gets without LimitNOFILE
    app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), "", web_static_dir=os.path.join(src, "web"))
    resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))  # this side needs more than 1,000 sockets
    try:
        if hard > 1024:
            check("open files limit raised from 1024 to the hard limit" in app.log_text(),
                  "epa serve raised its open-files soft limit from 1024 to the hard limit (logged)")
        held, refused = crowd_row(app, "1,000 slow connections from 100 addresses", [f"127.0.0.{10 + i}" for i in range(100)], seconds)
        check(held >= 900 and refused == 0,
              f"the many-address crowd was held open ({held} of 1,000, {refused} refused; each address is under its cap)")
        held, refused = crowd_row(app, "1,000 slow connections from one address", ["127.0.0.2"], seconds)
        check(refused >= 1000, f"one address past its cap of 32 is refused at once (503 {refused} times)")
        # Under a sanitizer every answer costs several times the CPU: a third of the crowd (the
        # same paths; what is judged there is memory, not capacity).
        readers = 500 if os.environ.get("EPA_SANITIZER_RUN") else 1500
        held, _ = crowd_row(app, f"{readers:,} slow readers from 50 addresses", [f"127.0.0.{120 + i}" for i in range(50)],
                            max(5, seconds * 2 // 3), readers=readers)
        check(held >= readers * 2 // 3, f"the slow readers were held open ({held} of {readers:,} at the median)")
        time.sleep(0.3)
        log = app.log_text()
        refusal_lines = [line for line in log.splitlines() if "too many from one address" in line]
        check(1 <= len(refusal_lines) <= 3, f"refusals from one address are logged as a count, not a line each "
                                            f"({len(refusal_lines)} lines)")
    finally:
        status = app.stop()
        check(status == 0, f"epa serve stopped cleanly (status {status})")
        if failures:
            print(app.log_text()[-3000:])
        app.remove()
    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
