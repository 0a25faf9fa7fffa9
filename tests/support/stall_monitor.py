"""Stalls of the machine a real-time test runs on, seen by processes that share nothing with the
appliance.

A hardware-in-the-loop test runs the appliance and its simulated I/O module on the same machine. On
a shared virtual machine the hypervisor sometimes stops a CPU for tens of milliseconds (this VM:
wake-ups up to 100 ms late on 2026-11-26). The appliance is then right to fault (io-errors,
overruns), as it would be if a real module went silent, but the test meant to check something
else. StallMonitor runs one process pinned to each CPU that sleeps 2 ms at a time and notes every
wake-up that came more than `threshold_ms` late; a test may retry a check once when its failure
came with such a stall, and must say so. A failure without a stall is a failure.
"""
import multiprocessing
import os
import time


def _watch(cpu, threshold_s, pipe):
    try:
        os.sched_setaffinity(0, {cpu})
    except OSError:
        pass  # fewer CPUs allowed than the machine has: watch where the kernel puts us
    period = 0.002
    last = time.monotonic()
    while True:
        time.sleep(period)
        now = time.monotonic()
        late = now - last - period
        if late > threshold_s:
            pipe.send((last + period, late))
        last = now


class StallMonitor:
    def __init__(self, threshold_ms=5.0):
        self.threshold_ms = threshold_ms
        self.stalls = []  # (monotonic time the wake-up was due, how late in seconds)
        self.pipes, self.procs = [], []
        cpus = sorted(os.sched_getaffinity(0))
        for cpu in cpus:
            receive, send = multiprocessing.Pipe(duplex=False)
            proc = multiprocessing.Process(target=_watch, args=(cpu, threshold_ms / 1000.0, send), daemon=True)
            proc.start()
            self.pipes.append(receive)
            self.procs.append(proc)

    def _drain(self):
        for pipe in self.pipes:
            while pipe.poll():
                self.stalls.append(pipe.recv())

    def stalls_since(self, t0):
        """The stalls whose wake-up was due at or after monotonic time t0: [(due, late_s)]."""
        self._drain()
        return [s for s in self.stalls if s[0] >= t0]

    @staticmethod
    def describe(stalls):
        if not stalls:
            return "no stall of the machine"
        worst = max(late for _, late in stalls)
        return f"{len(stalls)} stall(s) of the machine, the longest {worst * 1000:.0f} ms"

    def stop(self):
        for proc in self.procs:
            proc.terminate()
            proc.join(timeout=2)
