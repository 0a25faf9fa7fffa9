"""Stalls of the machine a real-time test runs on, seen by processes that share nothing with the
appliance.

A hardware-in-the-loop test runs the appliance and its simulated I/O module on the same machine. On
a shared virtual machine the hypervisor sometimes stops a CPU for tens of milliseconds (on a 2-core
VM: wake-ups up to 100 ms late). The appliance is then right to fault (io-errors,
overruns), as it would be if a real module went silent, but the test meant to check something
else. StallMonitor runs one process pinned to each CPU that sleeps 2 ms at a time and notes every
wake-up that came more than `threshold_ms` late; a test may retry a check once when its failure
came with the machine stalled for UNFIT_SHARE of the time or once for UNFIT_STALL_S, and must say so; failing
again on a machine as stalled, the check has no verdict and the test says so (ctest: skipped).
A failure on a machine that did not stall is a failure.

The watchers run at SCHED_FIFO priority 1 when allowed (root, as CI runs): above every ordinary
process, so a busy machine does not make them late, and below the appliance's loop and the
simulated module, which they never delay. A watcher late at that priority means the CPU itself
was taken away. Without the privilege they run as ordinary processes (`realtime` says which),
and then heavy load alone can make them late.
"""
import multiprocessing
import os
import time

# A real-time check that fails while the machine was stalled this share of its time or more is
# run once more; failing again on a machine as stalled, it has no verdict (SKIP_RETURN_CODE). A
# 2-core VM, idle: 0 % in a calm hour (no stall in 10 s), 0.9 % in a noisy one (8 stalls of
# 7-24 ms in 8 s).
UNFIT_SHARE = 0.01
# Or one stall this long: longer than the fault thresholds of the tests with relaxed I/O timing (20 ms
# per request) allow; a test whose appliance faults sooner gives its own (StallMonitor(unfit_stall_s)).
UNFIT_STALL_S = 0.05
SKIP_RETURN_CODE = 77


def _watch(cpu, threshold_s, pipe):
    try:
        os.sched_setaffinity(0, {cpu})
    except OSError:
        pass  # fewer CPUs allowed than the machine has: watch where the kernel puts us
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
        pipe.send(("realtime", True))
    except OSError:
        pipe.send(("realtime", False))
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
    def __init__(self, threshold_ms=5.0, unfit_stall_s=UNFIT_STALL_S):
        """unfit_stall_s: one stall this long makes the machine unfit; a test whose appliance faults
        sooner (a tighter I/O timing) gives its own."""
        self.threshold_ms = threshold_ms
        self.unfit_stall_s = unfit_stall_s
        self.stalls = []  # (monotonic time the wake-up was due, how late in seconds)
        self.worst_stall_ms = 0.0  # of the second run when judged() returned no verdict
        self.stalled_percent = 0.0
        self.realtime = []  # per watcher: whether it got SCHED_FIFO
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
            while not pipe.closed and pipe.poll():
                try:
                    first, second = pipe.recv()
                except EOFError:  # the watcher has ended
                    pipe.close()
                    break
                if first == "realtime":
                    self.realtime.append(second)
                else:
                    self.stalls.append((first, second))

    def stalls_since(self, t0):
        """The stalls whose wake-up was due at or after monotonic time t0: [(due, late_s)]."""
        self._drain()
        return [s for s in self.stalls if s[0] >= t0]

    @staticmethod
    def _share(stalls, t0):
        return min(1.0, sum(late for _, late in stalls) / max(time.monotonic() - t0, 1e-3))

    def stalled_share(self, t0):
        """The share of the time since monotonic t0 that the machine was seen stalled (0..1)."""
        return self._share(self.stalls_since(t0), t0)

    def unfit_since(self, t0):
        """Whether the machine stalled too much since t0 for a real-time result to mean anything."""
        stalls = self.stalls_since(t0)
        return self._share(stalls, t0) >= UNFIT_SHARE or any(late >= self.unfit_stall_s for _, late in stalls)

    def describe(self, t0):
        stalls = self.stalls_since(t0)
        how = "" if self.realtime and all(self.realtime) else " (watchers at normal priority: load alone can cause these)"
        if not stalls:
            return "no stall of the machine" + how
        worst = max(late for _, late in stalls)
        return (f"{len(stalls)} stall(s) of the machine of >= {self.threshold_ms:.0f} ms, the longest {worst * 1000:.0f} ms, "
                f"{100 * self._share(stalls, t0):.1f} % of the time" + how)

    def judged(self, name, attempt, before_retry=None):
        """The rule every real-time test here follows. attempt() returns its failures (a list of
        texts). When it failed on a machine unfit meanwhile, prints `RETRY:`, calls before_retry()
        and runs it once more. Returns (failures, no_verdict): no_verdict is the reason when the
        second run failed on a machine as unfit (its failures then mean nothing), else None."""
        t0 = time.monotonic()
        failures = attempt()
        if not failures or not self.unfit_since(t0):
            return failures, None
        print(f"RETRY: {name}: {'; '.join(failures)} -- with {self.describe(t0)}: run once more", flush=True)
        if before_retry:
            before_retry()
        t1 = time.monotonic()
        failures = attempt()
        if failures and self.unfit_since(t1):
            stalls = self.stalls_since(t1)
            self.worst_stall_ms = max(late for _, late in stalls) * 1000
            self.stalled_percent = 100 * self._share(stalls, t1)
            return failures, f"{name}: {'; '.join(failures)} -- again with {self.describe(t1)}"
        return failures, None

    def not_judged(self, test, no_verdict):
        """The one line a check without a verdict prints (the test then exits SKIP_RETURN_CODE, which
        ctest counts as skipped and scripts/test.sh counts as not judged): what stalled, how long."""
        line = (f"NOT JUDGED: {test}: the machine stalled {self.worst_stall_ms:.0f} ms at worst "
                f"({self.stalled_percent:.1f} % of the time) while it failed twice: {no_verdict}")
        print(line, flush=True)
        return line

    def stop(self):
        """Ends the watchers; what they saw stays readable."""
        self._drain()
        for proc in self.procs:
            proc.terminate()
            proc.join(timeout=2)
