#!/usr/bin/env bash
# Interoperability: Debian's mbpoll (a modpoll-style command-line Modbus master, libmodbus) against
# a running appliance on the simulated plant, as a SCADA engineer would poke it.
#
#   mbpoll_test.sh <epa binary> <source dir>
#
# Starts `epa serve` on a free loopback port with registers/epa.csv, waits for it by polling, and
# checks: the position float (input 0-1, ABCD, read with -B) is the simulated piston's (0 mm at
# start), mode RUN (which holds) and then a setpoint written as an ABCD float moves the piston there, an unmapped
# register is refused (exception 02) and the tuning register lc_mm is refused while locked
# (exception 04), 16 discrete inputs read in one request, and unit id 0 is answered with the
# version epa --version prints. The appliance is stopped by its PID (SIGTERM, SIGKILL after 5 s). Exit 0: all
# passed; 1: a check failed (each failure says what was expected and what came back).
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" mbpoll
test_arguments 2 "<epa binary> <source dir>" "$@"
host=127.0.0.1
need mbpoll
need python3
[ -f "$src/registers/epa.csv" ] || { echo "FAIL: $src/registers/epa.csv not found" >&2; exit 1; }

# mbpoll against the appliance: TCP, unit 1, 0-based (PDU) addresses, one poll, 1 s timeout.
mb() { mbpoll -m tcp -a 1 -p "$port" -0 -1 -o 1 "$@"; }

# The value mbpoll printed for reference $1 ("[0]: 	12.5" -> 12.5); empty when there is none.
value_of() { awk -v ref="[$1]:" '$1 == ref { print $2; exit }'; }

# |a - b| <= tol for decimal numbers.
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a != "" && d <= t) }'; }

read_position() { mb -t 3:float -B -r 0 -c 1 "$host" 2>&1 | value_of 0; }

# ---- start the appliance on a free loopback port (STOP), then one Modbus answer ----
start_appliance "$src/registers/epa.csv"
mbpoll -m tcp -a 1 -p "$port" -0 -1 -o 1 -t 3 -r 12 -c 1 "$host" >/dev/null 2>&1 || abort "the appliance did not answer a Modbus read"

# ---- (1) the position float, ABCD (-B), input register 0-1: the simulated piston at 0 mm ----
out=$(mb -t 3:float -B -r 0 -c 1 "$host" 2>&1)
rc=$?
pos=$(value_of 0 <<<"$out")
if [ $rc -eq 0 ] && near "$pos" 0 0.5; then
  pass "(1) position read with -t 3:float -B at input 0 is $pos mm (piston at rest at 0 mm)"
else
  fail "(1) position read with -t 3:float -B at input 0: expected 0 +- 0.5 mm, got '${pos}' (mbpoll exit $rc): $out"
fi
# The same point through mbpoll's default 1-based reference (30001), as most HMIs name it.
out=$(mbpoll -m tcp -a 1 -p "$port" -1 -o 1 -t 3:float -B -r 1 -c 1 "$host" 2>&1)
rc=$?
pos1=$(value_of 1 <<<"$out")
if [ $rc -eq 0 ] && near "$pos1" 0 0.5; then
  pass "(1) position read through the 1-based reference 30001 (-r 1, no -0) is $pos1 mm"
else
  fail "(1) position through the 1-based reference -r 1: expected 0 +- 0.5 mm, got '${pos1}' (mbpoll exit $rc): $out"
fi

# ---- (2) mode 1 (RUN, holding 2: enable holds the piston), then setpoint 120 mm (holding 0-1, float ABCD) moves it ----
out=$(mb -t 4 -r 2 "$host" 1 2>&1)
rc=$?
if [ $rc -eq 0 ] && grep -q "Written 1 references" <<<"$out"; then
  pass "(2) mode 1 (run) written at holding 2"
else
  fail "(2) writing mode 1 (-t 4 -r 2): expected success, mbpoll exit $rc: $out"
fi
out=$(mb -t 4:float -B -r 0 "$host" 120 2>&1)
rc=$?
if [ $rc -eq 0 ] && grep -q "Written 1 references" <<<"$out"; then
  pass "(2) setpoint 120 written as a float with -t 4:float -B at holding 0"
else
  fail "(2) writing setpoint 120 (-t 4:float -B -r 0): expected success, mbpoll exit $rc: $out"
fi
sp=$(mb -t 4:float -B -r 0 -c 1 "$host" 2>&1 | value_of 0)
if near "$sp" 120 0; then
  pass "(2) setpoint reads back as $sp"
else
  fail "(2) setpoint read back (-t 4:float -B -r 0): expected 120, got '${sp}'"
fi

# ---- (3) the simulated piston reaches 120 +- 3 mm within 15 s (polled every 0.2 s) ----
# Three polls in a row inside the band, so that the piston is there rather than swinging through
# (FF-IDZ overshoots on the paper's model: README, "FF-IDZ overshoot and settling").
deadline=$(( $(now_ms) + 15000 ))
start=$(now_ms)
pos=""
in_band=0
while [ "$(now_ms)" -lt "$deadline" ]; do
  pos=$(read_position)
  if near "$pos" 120 3; then in_band=$((in_band + 1)); else in_band=0; fi
  [ "$in_band" -ge 3 ] && break
  sleep 0.2
done
if [ "$in_band" -ge 3 ]; then
  pass "(3) position $pos mm within 3 mm of 120 (3 polls in a row) after $(( $(now_ms) - start )) ms"
else
  fail "(3) position did not stay within 3 mm of 120 for 3 polls in a row within 15 s: last read '${pos}' mm"
fi
mode=$(mb -t 4 -r 2 -c 1 "$host" 2>&1 | value_of 2)
if [ "$mode" = "1" ]; then
  pass "(3) mode reads 1 (run) after the move"
else
  fail "(3) mode after the move: expected 1 (run), got '${mode}' (a fault? see the log)"
  show_log
fi

# ---- (4) an unmapped register is refused with exception 02 (illegal data address) ----
out=$(mb -t 3 -r 199 -c 1 "$host" 2>&1)
rc=$?
if [ $rc -ne 0 ] && grep -qi "illegal data address" <<<"$out"; then
  pass "(4) reading unmapped input register 199 (below the fault history at 200): mbpoll exit $rc, $(grep -i 'illegal data address' <<<"$out")"
else
  fail "(4) reading unmapped input register 199 (below the fault history at 200): expected a non-zero exit and 'Illegal data address', got exit $rc: $out"
fi
out=$(mb -t 4 -r 15 -c 1 "$host" 2>&1)
rc=$?
if [ $rc -ne 0 ] && grep -qi "illegal data address" <<<"$out"; then
  pass "(4) reading unmapped holding register 15: refused with 'Illegal data address'"
else
  fail "(4) reading unmapped holding register 15: expected a non-zero exit and 'Illegal data address', got exit $rc: $out"
fi

# ---- (5) the tuning register lc_mm (holding 28-29) is refused while locked (exception 04) ----
out=$(mb -t 4:float -B -r 28 "$host" 7.5 2>&1)
rc=$?
if [ $rc -ne 0 ] && grep -qi "slave device or server failure" <<<"$out"; then
  pass "(5) writing lc_mm 7.5 while locked: mbpoll exit $rc, $(grep -i 'failed' <<<"$out")"
else
  fail "(5) writing lc_mm while locked: expected a non-zero exit and exception 04 'Slave device or server failure', got exit $rc: $out"
fi
lc=$(mb -t 4:float -B -r 28 -c 1 "$host" 2>&1 | value_of 28)
if near "$lc" 5 0.0001; then
  pass "(5) lc_mm still reads $lc (the refused write changed nothing)"
else
  fail "(5) lc_mm after the refused write: expected 5, got '${lc}'"
fi

# ---- (6) 16 discrete inputs in one read; unit id 0 is this device ----
out=$(mb -t 1 -r 0 -c 16 "$host" 2>&1)
rc=$?
io_ok=$(value_of 2 <<<"$out")
last=$(value_of 15 <<<"$out")
if [ $rc -eq 0 ] && [ "$io_ok" = "1" ] && [ -n "$last" ]; then
  pass "(6) discrete inputs 0-15 read in one request (-t 1 -c 16): io_ok [2] = $io_ok, [15] = $last"
else
  fail "(6) reading discrete inputs 0-15 (-t 1 -c 16): expected success with io_ok 1, got exit $rc: $out"
fi
out=$(mbpoll -m tcp -a 0 -p "$port" -0 -1 -o 1 -t 3 -r 12 -c 3 "$host" 2>&1)
rc=$?
version="$(value_of 12 <<<"$out").$(value_of 13 <<<"$out").$(value_of 14 <<<"$out")"
expected=$("$epa" --version | sed -n 's/^epa //p')
if [ $rc -eq 0 ] && [ "$version" = "$expected" ]; then
  pass "(6) unit id 0 (-a 0) answered: version registers 12-14 read $version, as epa --version"
else
  fail "(6) unit id 0 (-a 0), input 12-14: expected $expected (epa --version), got '$version' (exit $rc): $out"
fi

# ---- the appliance is still up and stops cleanly on SIGTERM ----
finish_test
