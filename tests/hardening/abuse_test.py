#!/usr/bin/env python3
"""Load and abuse: what a plant network throws at the appliance, while 8 valid clients poll it.

    abuse_test.py <epa binary> <source dir> <modbus_load binary> [seconds]

Two fresh appliances (sim plant, RUN at 100 mm, loop at SCHED_FIFO as shipped, max_clients 128,
the status page on), each measured over `seconds` (default 8) with 8 valid Modbus clients
(bench/modbus_load: FC3 reads of 10 registers in a closed loop) and the scan cycle's statistics
from its own registers:
  baseline  the 8 clients alone;
  abuse     the 8 clients plus 100 idle connections, a client that sends one byte a second, a
            flood of invalid frames (garbage, bad MBAP headers, unknown functions, truncated
            frames) on reconnecting connections, a flood of illegal writes (read-only and unmapped
            registers, out-of-range values, locked tuning), and an HTTP flood (status polls,
            commands without a token, malformed requests, unknown paths, oversized bodies).
Bounds (checked): nothing crashes; the valid clients see no errors and a p99 latency under 20 ms;
the scan cycle has no overrun fault (no 10 missed 5 ms deadlines in a row); the slow client and
the floods are answered or dropped, never served at the expense of the valid ones.
The scan period's p99 jitter under abuse (its bound: 1 ms, 20 % of Ts) is a timing target, judged
by bench/abuse_jitter.sh on the median of several runs, not here: on a shared VM
one run can meet a stall of the whole machine (wake-ups 100 ms late, or 3 ms p99 jitter
with the 8 clients alone), which says nothing about the appliance. The floods'
loopback traffic is handled in softirq context, which preempts even the SCHED_FIFO loop.
Prints both columns; exit 1 on any failure.
"""
import json
import multiprocessing
import os
import random
import socket
import struct
import subprocess
import sys
import threading
import time
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, UNIT, Appliance, f32_value, f32_words, u32_value  # noqa: E402


def loop_stats(app):
    r = app.client.read_input_registers(90, 12, slave=UNIT).registers
    return {"wake_p99_us": f32_value(r[2:4], "ABCD"), "wake_max_us": f32_value(r[4:6], "ABCD"),
            "jitter_p99_us": f32_value(r[6:8], "ABCD"), "overruns": u32_value(r[10:12])}


def flood_invalid_frames(port, seconds, counter):
    """Garbage on reconnecting connections: counts frames sent."""
    rng = random.Random(1)
    end = time.monotonic() + seconds
    frames = [
        lambda: bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 40))),                       # noise
        lambda: struct.pack(">HHHB", rng.getrandbits(16), 7, 6, 1) + b"\x03\x00\x00\x00\x01",       # protocol id 7
        lambda: struct.pack(">HHHB", 1, 0, 300, 1) + b"\x03\x00\x00",                               # length too big
        lambda: struct.pack(">HHHB", 1, 0, 2, 1) + b"\x63",                                         # unknown function 0x63
        lambda: struct.pack(">HHHB", 1, 0, 6, 1) + b"\x03\x00",                                     # truncated
        lambda: struct.pack(">HHHB", 1, 0, 6, 1) + b"\x03\xff\xff\x00\x7d",                        # address + quantity past 65535
    ]
    while time.monotonic() < end:
        try:
            with socket.create_connection((HOST, port), timeout=0.5) as s:
                s.settimeout(0.002)
                for _ in range(50):
                    s.sendall(rng.choice(frames)())
                    counter.value += 1
                    try:
                        s.recv(512)
                    except (socket.timeout, OSError):
                        pass
        except OSError:
            time.sleep(0.01)


def flood_illegal_writes(port, seconds, counter):
    from pymodbus.client import ModbusTcpClient
    c = ModbusTcpClient(HOST, port=port, timeout=1)
    c.connect()
    end = time.monotonic() + seconds
    writes = [
        lambda: c.write_registers(0, f32_words(9999.0, "ABCD"), slave=UNIT),  # setpoint out of range
        lambda: c.write_register(2, 7, slave=UNIT),                            # mode out of range
        lambda: c.write_registers(20, f32_words(2.0, "ABCD"), slave=UNIT),     # tuning, locked
        lambda: c.write_register(9, 1234, slave=UNIT),                         # wrong unlock key
        lambda: c.write_register(1, 0, slave=UNIT),                            # half of a float
        lambda: c.write_register(500, 1, slave=UNIT),                          # unmapped
        lambda: c.write_coil(40, True, slave=UNIT),                            # unmapped coil
    ]
    while time.monotonic() < end:
        rr = random.choice(writes)()
        counter.value += 1
        if not rr.isError():
            raise SystemExit(f"an illegal write was accepted: {rr}")
    c.close()


def flood_http(port, seconds, counter):
    """Four connections' worth of requests at once; an oversized body that never comes holds one
    worker for its read timeout, the others carry on."""
    threads = [threading.Thread(target=http_worker, args=(port, seconds, counter, i)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()


def http_worker(port, seconds, counter, seed):
    end = time.monotonic() + seconds
    requests = [
        b"GET /api/status HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n",
        b"GET /api/trend HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n",
        b"POST /api/setpoint HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 20\r\n\r\n{\"setpoint_mm\":120}",
        b"GET /../../etc/passwd HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n",
        b"GARBAGE\r\n\r\n",
        b"POST /api/mode HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 100000\r\n\r\n" + b"x" * 8192,
        b"GET /nothing-here HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n",
    ]
    rng = random.Random(seed)
    while time.monotonic() < end:
        try:
            with socket.create_connection((HOST, port), timeout=1) as s:
                s.settimeout(1)
                s.sendall(rng.choice(requests))
                s.recv(65536)
                with counter.get_lock():
                    counter.value += 1
        except OSError:
            time.sleep(0.005)


def slow_client(port, seconds, sent):
    """One byte of a valid FC3 request per second: it must never hold up anyone else."""
    frame = struct.pack(">HHHB", 9, 0, 6, UNIT) + b"\x03\x00\x00\x00\x01"
    with socket.create_connection((HOST, port), timeout=2) as s:
        for i in range(min(len(frame), int(seconds))):
            try:
                s.sendall(frame[i:i + 1])
            except OSError:
                return  # the server dropped it (its request timeout): what it should do
            sent[0] += 1
            time.sleep(1.0)


def measure(epa, src, load, seconds, abuse):
    app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), "", web_static_dir=os.path.join(src, "web"),
                    # One host opens every connection here (the valid clients and the abuse): the
                    # per-address cap is lifted, as this measures the server's capacity, not the
                    # slot policy (hardening.fair_slots judges that).
                    modbus_extra="max_clients = 128\nmax_clients_per_address = 128\nidle_timeout_s = 120\n")
    procs, idle, counters = [], [], {}
    try:
        app.client.write_registers(0, f32_words(100.0, "ABCD"), slave=UNIT)
        app.client.write_register(2, 1, slave=UNIT)
        slow_sent = [0]
        if abuse:
            for _ in range(100):
                idle.append(socket.create_connection((HOST, app.port), timeout=2))
            threading.Thread(target=slow_client, args=(app.port, seconds, slow_sent), daemon=True).start()
            for name, target, port in (("invalid frames", flood_invalid_frames, app.port),
                                       ("illegal writes", flood_illegal_writes, app.port),
                                       ("http requests", flood_http, app.web_port)):
                counters[name] = multiprocessing.Value("q", 0)
                p = multiprocessing.Process(target=target, args=(port, seconds + 1.5, counters[name]), daemon=True)
                p.start()
                procs.append((name, p))
        out = subprocess.run([load, "--port", str(app.port), "--clients", "8", "--seconds", str(seconds), "--warmup", "1"],
                             capture_output=True, text=True, timeout=seconds + 30)
        result = json.loads(out.stdout.strip().splitlines()[-1]) if out.returncode == 0 else {"error": out.stderr}
        for name, p in procs:
            p.join(timeout=10)
            result[f"{name} exit"] = p.exitcode
        result.update(loop_stats(app))
        result["fault_code"] = app.client.read_input_registers(10, 1, slave=UNIT).registers[0]
        result["clients_now"] = app.client.read_input_registers(126, 1, slave=UNIT).registers[0]
        with urllib.request.urlopen(f"http://{HOST}:{app.web_port}/api/status", timeout=2) as r:
            result["page_ok"] = json.load(r)["mode"] == "run"
        result["alive"] = app.proc.poll() is None
        result["counts"] = {k: v.value for k, v in counters.items()}
        result["counts"]["idle connections"] = len(idle)
        result["counts"]["slow client bytes"] = slow_sent[0]
        return result
    finally:
        for s in idle:
            s.close()
        for _, p in procs:
            if p.is_alive():
                p.terminate()
        app.stop()
        app.remove()


def main():
    args = sys.argv[1:]
    if len(args) not in (3, 4):
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir> <modbus_load binary> [seconds]")
    epa, src, load = (os.path.abspath(a) for a in args[:3])
    seconds = float(args[3]) if len(args) == 4 else 8.0
    base = measure(epa, src, load, seconds, abuse=False)
    hit = measure(epa, src, load, seconds, abuse=True)
    failures = []
    for label, r in (("baseline", base), ("abuse", hit)):
        if "error" in r:
            failures.append(f"{label}: the valid clients failed: {r['error']}")
            continue
        if r["errors"]:
            failures.append(f"{label}: {r['errors']} errors for the valid clients")
        if r["p99_us"] > 20000:
            failures.append(f"{label}: valid clients' p99 {r['p99_us']} us > 20 ms")
        if not r["alive"] or r["fault_code"] != 0 or not r["page_ok"]:
            failures.append(f"{label}: alive {r['alive']}, fault code {r['fault_code']}, page in RUN {r['page_ok']}")
        for k, v in r.items():
            if k.endswith(" exit") and v != 0:
                failures.append(f"{label}: the {k[:-5]} flood ended with {v}")
    if "error" not in hit and "error" not in base:
        print(f"{'':34}{'8 clients':>14}{'8 clients + abuse':>20}")
        for key, name in (("throughput_rps", "valid requests/s"), ("p50_us", "valid p50 latency (us)"),
                          ("p99_us", "valid p99 latency (us)"), ("max_us", "valid max latency (us)"),
                          ("jitter_p99_us", "scan period jitter p99 (us)"), ("wake_p99_us", "scan wake-up p99 (us)"),
                          ("wake_max_us", "scan wake-up max (us)"), ("overruns", "scan overruns")):
            print(f"{name:34}{base[key]:>14.0f}{hit[key]:>20.0f}")
        print("abuse sent: " + ", ".join(f"{k} {v}" for k, v in hit["counts"].items()))
        print(f"jitter: baseline {base['jitter_p99_us']:.0f} us, abuse {hit['jitter_p99_us']:.0f} us (p99; "
              "its bound is judged over several runs by bench/abuse_jitter.sh)")
    for f in failures:
        print("FAIL:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
