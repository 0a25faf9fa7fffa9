"""Runs one real-time test program under the stall rule (stall_monitor.StallMonitor.judged).

    python3 stall_judged.py NAME PROGRAM [ARGS...]

For a real-time test that is a program of its own (a gtest executable), so that it follows the
same rule as the Python real-time tests instead of a copy of it: a run that fails while the
machine itself stalled is run once more; failing again on a machine as stalled, it has no verdict
(exit SKIP_RETURN_CODE, ctest: skipped). Otherwise the exit code is the program's own, and a
failure on a machine that did not stall is a failure.
"""
import subprocess
import sys

from stall_monitor import SKIP_RETURN_CODE, StallMonitor


def main(argv):
    if len(argv) < 3:
        print("usage: stall_judged.py NAME PROGRAM [ARGS...]", file=sys.stderr)
        return 2
    name, command = argv[1], argv[2:]
    exit_codes = []

    def attempt():
        code = subprocess.run(command, check=False).returncode
        exit_codes.append(code)
        return [] if code == 0 else [f"{command[0]} exited {code}"]

    monitor = StallMonitor()
    try:
        failures, no_verdict = monitor.judged(name, attempt)
    finally:
        monitor.stop()
    if no_verdict:
        print(f"NO VERDICT: {no_verdict}", flush=True)
        return SKIP_RETURN_CODE
    if failures:
        print(f"FAILED: {name}: {'; '.join(failures)}", flush=True)
    return exit_codes[-1]


if __name__ == "__main__":
    sys.exit(main(sys.argv))
