#!/usr/bin/env python3
"""Fair Modbus connection slots and a lock-out that does not lock out the right key, tried as a
hostile client on the plant network would: raw sockets and hand-built frames (nothing of the
project's Modbus code), against `epa serve` on loopback with the shipped limits (max_clients 16,
max_clients_per_address 4).

  slots    A 1 s HMI on one persistent connection (FC3 once a second) and one that connects per
           poll, both from 127.0.0.1, while busy-looking attackers read every 0.5-2 s and reconnect
           when evicted or refused: 16 from 16 addresses, 64 from 64 addresses (127.0.0.2 ...), and
           64 from one address. Each HMI's polls are answered within 1 s at least 95 % of the time
           (the connect-per-poll HMI starts 1 s after the crowd: the crowd's arrival is one burst).
  lockout  An attacker on the engineer's address (127.0.0.1) guesses 10 keys a second, reconnecting
           for each guess, then on one connection; meanwhile the engineer opens a connection, holds
           it 2 s and writes the right key, a try every 1.25 s. At least 95 % of the engineer's tries
           unlock, and at least 80 % of the attacker's guesses are refused unseen (04).

    fair_slots_test.py <epa binary> <source dir> slots|lockout [SECONDS_PER_ROW]

Loopback only (Linux routes all of 127/8 to lo; the clients bind their source address), every
loop bounded; the appliance is stopped by its PID. Exit 0 when every row holds, 1 otherwise.
"""
import os
import random
import socket
import struct
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, UNIT, UNLOCK_ADDRESS, UNLOCK_KEY, Appliance, Checks, key_words  # noqa: E402

check = Checks()


# ---- raw Modbus TCP ----
def fc3(tid, address=2, count=1):
    return struct.pack(">HHHBBHH", tid & 0xFFFF, 0, 6, UNIT, 0x03, address, count)


def fc16(tid, address, words):
    pdu = struct.pack(">BHHB", 0x10, address, len(words), 2 * len(words)) + b"".join(struct.pack(">H", w) for w in words)
    return struct.pack(">HHHB", tid & 0xFFFF, 0, len(pdu) + 1, UNIT) + pdu


def read_answer(s):
    """(function code, payload) of one whole answer; ConnectionError when the appliance closed."""
    data = b""
    while len(data) < 7 or len(data) < 6 + struct.unpack(">H", data[4:6])[0]:
        chunk = s.recv(300)
        if not chunk:
            raise ConnectionError("closed by the appliance")
        data += chunk
    return data[7], data[8:]


def exception_of(answer):
    fc, payload = answer
    return payload[0] if fc & 0x80 else 0


def connect(port, source="127.0.0.1", timeout=1.0):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.settimeout(timeout)
    s.bind((source, 0))
    s.connect((HOST, port))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


# ---- slots ----
def attacker(port, source, stop):
    """Reads every 0.5-2 s; when evicted or refused, connects again at once (after 0.1 s)."""
    tid = 0
    while not stop.is_set():
        try:
            s = connect(port, source)
        except OSError:
            stop.wait(0.1)
            continue
        try:
            while not stop.is_set():
                tid += 1
                s.sendall(fc3(tid))
                read_answer(s)
                stop.wait(random.uniform(0.5, 2.0))
        except OSError:
            stop.wait(0.1)
        finally:
            s.close()


def persistent_hmi(port, seconds, result):
    """FC3 once a second on one connection (reconnecting if dropped): [served, polls]."""
    s = None
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        t0 = time.monotonic()
        result[1] += 1
        try:
            if s is None:
                s = connect(port)
            s.sendall(fc3(result[1]))
            if exception_of(read_answer(s)) == 0 and time.monotonic() - t0 <= 1.0:
                result[0] += 1
        except OSError:
            if s:
                s.close()
            s = None
        time.sleep(max(0.0, 1.0 - (time.monotonic() - t0)))
    if s:
        s.close()


def per_poll_hmi(port, seconds, result):
    """Connects, reads once and closes, once a second: [served, polls]. A connection the appliance
    closes at once (full while others arrive) is tried again, as such a client does; the poll
    counts only if answered within 1 s of its first try."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        t0 = time.monotonic()
        result[1] += 1
        for attempt in range(2):
            try:
                with connect(port) as s:
                    s.sendall(fc3(result[1]))
                    code = exception_of(read_answer(s))
                    if code == 0 and time.monotonic() - t0 <= 1.0:
                        result[0] += 1
                    else:
                        print(f"  connect-per-poll HMI poll {result[1]}: exception {code}, {time.monotonic() - t0:.3f} s")
                break
            except OSError as e:
                print(f"  connect-per-poll HMI poll {result[1]} try {attempt + 1}: {e!r} after {time.monotonic() - t0:.3f} s")
        time.sleep(max(0.0, 1.0 - (time.monotonic() - t0)))


def slots_row(app, attackers, sources, seconds):
    persistent, per_poll = [0, 0], [0, 0]
    hmis = [threading.Thread(target=persistent_hmi, args=(app.port, seconds, persistent)),
            threading.Thread(target=per_poll_hmi, args=(app.port, seconds, per_poll))]
    hmis[0].start()  # the plant's HMI is connected before the crowd arrives
    time.sleep(0.3)
    stop = threading.Event()
    crowd = [threading.Thread(target=attacker, args=(app.port, sources[i % len(sources)], stop), daemon=True) for i in range(attackers)]
    for t in crowd:
        t.start()
    # The connect-per-poll HMI polls the crowd's steady state: a poll in the very instant 64
    # clients connect at once competes with them for the free slots, and the first comers win.
    time.sleep(1.0)
    hmis[1].start()
    for t in hmis:
        t.join(timeout=seconds + 10)
    stop.set()
    for t in crowd:
        t.join(timeout=5)
    where = f"{len(sources)} address{'es' if len(sources) > 1 else ''}"
    for name, (served, total) in (("persistent", persistent), ("connect-per-poll", per_poll)):
        check(total > 0 and served >= 0.95 * total,
              f"{attackers} busy attackers from {where}: the {name} HMI served within 1 s in {served} of {total} polls")
    time.sleep(1.0)


def slots(app, seconds):
    many = [f"127.0.0.{i}" for i in range(2, 201)]
    slots_row(app, 16, many[:16], seconds)
    slots_row(app, 64, many[:64], seconds)
    slots_row(app, 64, ["127.0.0.2"], seconds)
    time.sleep(0.5)
    log = app.log_text()
    lines = [line for line in log.splitlines() if "evicted and" in line and "refused in the last" in line]
    check(0 < len(lines) <= 2 + int(3 * (seconds + 2) / 60),
          f"evictions and refusals are told in summary lines, one a minute at most: {len(lines)} ({lines[:2]})")
    check(log.count("disconnected (") <= 20 * (1 + int(3 * (seconds + 2) / 60)), "disconnect lines are bounded")


# ---- lockout ----
def guesser(port, reconnect, stop, codes):
    """10 wrong keys a second from 127.0.0.1: each on a new connection, or all on one."""
    key = int(UNLOCK_KEY, 16)
    s, tid = None, 0
    while not stop.is_set():
        tid += 1
        t0 = time.monotonic()
        try:
            if s is None:
                s = connect(port)
            s.sendall(fc16(tid, UNLOCK_ADDRESS, key_words("%016x" % (key ^ (tid << 8) ^ 0x5A5A0000))))
            codes.append(exception_of(read_answer(s)))
        except OSError:
            if s:
                s.close()
            s = None
        if reconnect and s:
            s.close()
            s = None
        stop.wait(max(0.0, 0.1 - (time.monotonic() - t0)))
    if s:
        s.close()


def engineer_try(port, results):
    """A connection held 2 s (reading, as an engineering tool does), then the right key."""
    try:
        with connect(port, timeout=2.0) as s:
            s.sendall(fc3(1))
            read_answer(s)
            time.sleep(2.1)
            s.sendall(fc16(2, UNLOCK_ADDRESS, key_words()))
            results.append(exception_of(read_answer(s)))
    except OSError as e:
        results.append(f"error: {e}")


def lockout_row(app, reconnect, seconds):
    codes, tries = [], []
    stop = threading.Event()
    g = threading.Thread(target=guesser, args=(app.port, reconnect, stop, codes))
    g.start()
    time.sleep(1.0)  # the address is in back-off before the engineer starts
    engineers = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        t = threading.Thread(target=engineer_try, args=(app.port, tries))
        t.start()
        engineers.append(t)
        time.sleep(1.25)
    for t in engineers:
        t.join(timeout=10)
    stop.set()
    g.join(timeout=5)
    how = "reconnecting for each guess" if reconnect else "on one connection"
    unlocked = tries.count(0)
    check(tries and unlocked >= 0.95 * len(tries),
          f"attacker {how} on the engineer's address: the right key unlocked {unlocked} of {len(tries)} tries ({sorted(set(map(str, tries)))})")
    unseen = codes.count(4)
    check(codes and unseen >= 0.8 * len(codes),
          f"... and {unseen} of the attacker's {len(codes)} guesses were refused unseen (04), {codes.count(3)} looked at (03)")


def main():
    if len(sys.argv) not in (4, 5) or sys.argv[3] not in ("slots", "lockout"):
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir> slots|lockout [SECONDS_PER_ROW]")
    epa, src, part = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
    seconds = float(sys.argv[4]) if len(sys.argv) == 5 else (14.0 if part == "slots" else 18.0)
    random.seed(7)
    app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), "", modbus_extra="max_clients = 16\nmax_clients_per_address = 4\n")
    try:
        if part == "slots":
            slots(app, seconds)
        else:
            lockout_row(app, True, seconds)
            lockout_row(app, False, seconds)
        check(app.proc.poll() is None, "the appliance is still running")
    finally:
        app.stop()
        app.remove()
    print(f"{part}: {len(check.failures)} of the rows failed" if check.failures else f"{part}: every row held")
    sys.exit(1 if check.failures else 0)


if __name__ == "__main__":
    main()
