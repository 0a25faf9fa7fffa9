#!/usr/bin/env bash
# After a ctest run: how many real-time tests had no verdict because the machine itself stalled
# (each printed one `NOT JUDGED: <test>: ...` line and exited 77, which ctest counts as skipped;
# tests/support/stall_monitor.py). Prints the count (0 when none) and the lines; always exits 0,
# as a run that judged everything it could is not a failure.
# Usage: not_judged.sh BUILD_DIR [WHAT]   (WHAT names the run in the output, e.g. test.sh)
log=$1/Testing/Temporary/LastTest.log
what=${2:-ctest}
lines=$(grep -h '^NOT JUDGED: ' "$log" 2>/dev/null)
tests=$(sed -n 's/^NOT JUDGED: \([^:]*\):.*/\1/p' <<<"$lines" | sort -u)
count=$(grep -c . <<<"$tests")
if [ "$count" -eq 0 ]; then
  echo "$what: 0 tests not judged (every real-time check ran on a machine fit to judge it)"
else
  echo "$what: $count test(s) NOT JUDGED, the machine stalled (ctest: skipped, not passed): $(tr '\n' ' ' <<<"$tests")"
  echo "$lines"
fi
exit 0
