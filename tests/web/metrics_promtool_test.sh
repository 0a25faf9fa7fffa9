#!/usr/bin/env bash
# /metrics as Prometheus' own linter reads it: `promtool check metrics` (Debian's prometheus
# package) on what a running appliance serves, so base units, _total counters, HELP and TYPE are
# checked by the tool a site's monitoring uses, not by our reading of its rules.
#
#   metrics_promtool_test.sh <epa binary> <source dir>
#
# Starts `epa serve` (sim, RUN, setpoint 50 mm; Modbus and web on free loopback ports), waits for
# it by polling, lets it finish a move (so the counters and the move metrics are not all 0), then
# pipes /metrics into promtool; a Modbus request and an exception go first, so their counters
# count. Fails when promtool is missing (it is not skipped). The appliance is stopped by its PID.
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" promtool
test_arguments 2 "<epa binary> <source dir>" "$@"
host=127.0.0.1
need promtool prometheus
need curl
need mbpoll

http_get() { curl -s --max-time 2 "$1" 2>/dev/null; }

web_static_dir="$src/web"
start_appliance "$src/registers/epa.csv" "" --mode run --setpoint 50
modbus_port=$port
url=${url%/}
mbpoll -m tcp -a 1 -p "$modbus_port" -0 -1 -o 1 -t 3 -r 0 -c 2 "$host" >/dev/null 2>&1 || fail "a Modbus read of input 0-1 was refused"
mbpoll -m tcp -a 1 -p "$modbus_port" -0 -1 -o 1 -t 3 -r 199 -c 1 "$host" >/dev/null 2>&1 && fail "input 199 (unmapped) was answered"
deadline=$(( $(now_ms) + 10000 ))
metrics=""
while [ "$(now_ms)" -lt "$deadline" ]; do
  metrics=$(http_get "$url/metrics")
  grep -q '^epa_moves_total [1-9]' <<<"$metrics" && break
  sleep 0.2
done
grep -q '^epa_moves_total [1-9]' <<<"$metrics" || fail "epa_moves_total did not count the start-up move within 10 s"

# ---- promtool on /metrics ----
out=$(promtool check metrics <<<"$metrics" 2>&1)
rc=$?
if [ $rc -eq 0 ] && [ -z "$out" ]; then
  pass "promtool check metrics: no problems in $(grep -c '^# TYPE' <<<"$metrics") metrics"
else
  fail "promtool check metrics (exit $rc): $out"
  echo "---- /metrics ----" >&2
  echo "$metrics" >&2
fi
# What promtool cannot know: the values are in base units and the counters counted.
for want in '^epa_build_info{version="[0-9]+\.[0-9]+\.[0-9]+"} 1$' '^epa_position_meters 0\.0[0-9]*' '^epa_modbus_requests_total [1-9]' \
            '^epa_modbus_exceptions_total [1-9]' '^epa_web_requests_total [1-9]' '^# HELP epa_moves_total moves finished since start'; do
  grep -Eq "$want" <<<"$metrics" && pass "/metrics has $want" || fail "/metrics has no line matching $want"
done
version=$("$epa" --version | sed -n 's/^epa //p')
grep -qF "epa_build_info{version=\"$version\"} 1" <<<"$metrics" && pass "epa_build_info names $version, as epa --version" \
  || fail "epa_build_info does not name $version (epa --version)"

kill -0 "$pid" 2>/dev/null && pass "the appliance is still running" || fail "the appliance died during the test"
stop_appliance
[ "$failed" -eq 0 ] || show_log
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
