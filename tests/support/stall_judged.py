"""Runs one real-time test program under the stall rule (stall_monitor.StallMonitor.judged).

    python3 stall_judged.py [--unfit-stall-ms MS] NAME PROGRAM [ARGS...]

For a real-time test that is a program of its own (a gtest executable), so that it follows the
same rule as the Python real-time tests instead of a copy of it: a run that fails while the
machine itself stalled is run once more; failing again on a machine as stalled, it has no verdict
(exit SKIP_RETURN_CODE, ctest: skipped). Otherwise the exit code is the program's own, and a
failure on a machine that did not stall is a failure. --unfit-stall-ms: one stall this long makes
the machine unfit (default stall_monitor.UNFIT_STALL_S), for a program whose appliance faults
sooner than that when its module falls silent.
"""
import subprocess
import sys
import time

from stall_monitor import SKIP_RETURN_CODE, UNFIT_STALL_S, StallMonitor


def main(argv):
    unfit_stall_s = UNFIT_STALL_S
    if len(argv) > 2 and argv[1] == "--unfit-stall-ms":
        unfit_stall_s = float(argv[2]) / 1000.0
        argv = argv[:1] + argv[3:]
    if len(argv) < 3:
        print("usage: stall_judged.py [--unfit-stall-ms MS] NAME PROGRAM [ARGS...]", file=sys.stderr)
        return 2
    name, command = argv[1], argv[2:]
    exit_codes = []

    def attempt():
        code = subprocess.run(command, check=False).returncode
        exit_codes.append(code)
        return [] if code == 0 else [f"{command[0]} exited {code}"]

    monitor = StallMonitor(unfit_stall_s=unfit_stall_s)
    t0 = time.monotonic()
    try:
        failures, no_verdict = monitor.judged(name, attempt)
        print(f"the machine during {name}: {monitor.describe(t0)}", flush=True)
    finally:
        monitor.stop()
    if no_verdict:
        monitor.not_judged(name, no_verdict)
        return SKIP_RETURN_CODE
    if failures:
        print(f"FAILED: {name}: {'; '.join(failures)}", flush=True)
    return exit_codes[-1]


if __name__ == "__main__":
    sys.exit(main(sys.argv))
