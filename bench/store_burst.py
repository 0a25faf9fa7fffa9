#!/usr/bin/env python3
"""Does the store's work show in the scan cycle? Its p99 and max period jitter idle and under a
burst of 1,000 tuning writes over Modbus (each one audited and committed to SQLite with a full
sync by the store thread).

    bench/store_burst.py [seconds] [rounds]     (defaults 10 and 3; run as root for SCHED_FIFO)

Each measurement gets a fresh appliance (the loop's histograms count from start-up): `epa serve`
on the sim plant, RUN at 100 mm, the loop at SCHED_FIFO 80 with memory locked and the PM QoS
request as config/epa.toml ships them. Idle: it runs `seconds` and the loop statistics are read
from its input registers (loop_wake_p99_us 92, loop_wake_max_us 94, loop_jitter_p99_us 96,
loop_compute_p99_us 98, loop_overruns 100). Burst: the same, with 1,000 writes of m_r sent back
to back at the start, and the time until saved_counter reports all of them on disk. Rounds
alternate idle and burst. Loopback only; every appliance is stopped by its PID.
"""
import os
import statistics
import struct
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "support"))
from epa_appliance import UNIT, Appliance, unlock, f32_value, f32_words, u32_value  # noqa: E402

REPO = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
EPA = os.path.join(REPO, "build", "release", "src", "app", "epa")
WRITES = 1000


def loop_stats(c):
    rr = c.read_input_registers(90, 12, slave=UNIT)
    r = rr.registers
    return {"wake_p99": f32_value(r[2:4], "ABCD"), "wake_max": f32_value(r[4:6], "ABCD"),
            "jitter_p99": f32_value(r[6:8], "ABCD"), "compute_p99": f32_value(r[8:10], "ABCD"),
            "overruns": u32_value(r[10:12])}


def counters(c):
    a = c.read_input_registers(122, 2, slave=UNIT).registers
    s = c.read_input_registers(128, 2, slave=UNIT).registers
    return u32_value(a), u32_value(s)


def measure(seconds, burst):
    app = Appliance(EPA, os.path.join(REPO, "registers", "epa.csv"), "[loop]\nrealtime_priority = 80\n")
    try:
        c = app.client
        t0 = time.monotonic()
        c.write_registers(0, f32_words(100.0, "ABCD"), slave=UNIT)  # setpoint, then RUN
        c.write_register(2, 1, slave=UNIT)
        result = {}
        if burst:
            unlock(c)
            start = time.monotonic()
            busy = 0
            for i in range(WRITES):
                value = struct.unpack(">f", struct.pack(">f", 1.5 + (i % 100) * 0.001))[0]
                while True:
                    rr = c.write_registers(20, f32_words(value, "ABCD"), slave=UNIT)
                    if not rr.isError():
                        break
                    # 06 (busy): the loop takes at most 64 commands per 5 ms cycle; a client retries.
                    if getattr(rr, "exception_code", None) != 6:
                        raise RuntimeError(f"write {i} refused: {rr}")
                    busy += 1
                    time.sleep(0.001)
            result["burst_s"] = time.monotonic() - start
            result["busy"] = busy
            while True:
                accepted, saved = counters(c)
                if saved >= accepted or time.monotonic() - start > 30:
                    break
                time.sleep(0.001)
            result["all_saved_s"] = time.monotonic() - start
            result["saved"] = saved
        time.sleep(max(0.0, seconds - (time.monotonic() - t0)))
        result.update(loop_stats(c))
        return result
    finally:
        app.stop()
        app.remove()


def main():
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    subprocess.run(["cmake", "--build", "--preset", "release", "--target", "epa"], cwd=REPO, check=True,
                   stdout=subprocess.DEVNULL)
    if os.geteuid() != 0:
        print("warning: not root: the loop runs without SCHED_FIFO and memory locking", file=sys.stderr)
    idle, burst = [], []
    for r in range(rounds):
        idle.append(measure(seconds, False))
        burst.append(measure(seconds, True))
        print(f"round {r + 1}: idle jitter p99 {idle[-1]['jitter_p99']:.1f} us max wake {idle[-1]['wake_max']:.0f} us; "
              f"burst jitter p99 {burst[-1]['jitter_p99']:.1f} us max wake {burst[-1]['wake_max']:.0f} us, "
              f"{WRITES} writes in {burst[-1]['burst_s']:.2f} s ({burst[-1]['busy']} busy answers retried), all on disk after {burst[-1]['all_saved_s']:.2f} s",
              file=sys.stderr)
    med = lambda rows, k: statistics.median(row[k] for row in rows)  # noqa: E731
    print(f"\nscan cycle over {seconds:g} s, median of {rounds} fresh appliances each (loop at Ts = 5 ms):")
    print(f"{'':28}{'idle':>10}{'1,000-write burst':>20}{'ratio':>8}")
    for key, name in (("wake_p99", "wake-up p99 (us)"), ("jitter_p99", "period jitter p99 (us)"),
                      ("wake_max", "wake-up max (us)"), ("compute_p99", "compute p99 (us)"), ("overruns", "overruns")):
        i, b = med(idle, key), med(burst, key)
        ratio = f"{b / i:.2f}" if i else "-"
        print(f"{name:28}{i:>10.1f}{b:>20.1f}{ratio:>8}")
    print(f"burst: {WRITES} Modbus writes in {med(burst, 'burst_s'):.2f} s; all {WRITES} on disk (saved_counter) "
          f"{med(burst, 'all_saved_s'):.2f} s after the first")


if __name__ == "__main__":
    main()
