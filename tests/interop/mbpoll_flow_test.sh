#!/usr/bin/env bash
# Interoperability, the whole integration with Debian's mbpoll (libmodbus; one connection per call,
# as a commissioning engineer scripts it), against a running appliance on the simulated plant.
#
#   mbpoll_flow_test.sh <epa binary> <source dir>
#
# `epa serve` on a free loopback port with registers/epa.csv, [limits] soft_max_mm = 300 and
# heartbeat_timeout_s = 5 (a background loop writes the heartbeat with mbpoll every 0.2 s), stopped
# by its PID at the end. Steps, in order, every address looked up by name in `epa registers --csv`:
# (1) the map; (2) the version registers = epa --version (mbpoll has no FC43: said, not tested);
# (3) mode RUN; (4) the unlock is per connection, so mbpoll (a new connection per call) cannot write
# a position record: checked that the write after an unlock call is refused (exception 04); record 1
# is written as an HMI would, over the web API (curl, with the token), and mbpoll reads it back;
# (5) the setpoint (record 0) moves the piston, then the start/ack handshake on record 1;
# (6) halt of a setpoint move; (7) jog_plus in MANUAL held with keep-alive writes, then released;
# (8) a soft-limit fault (MANUAL, valve 1.5 V), reset by the control word's reset bit, and the
# fault history (count + newest entry). Each step prints its timing. Exit 0: all passed.
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" mbpoll-flow
test_arguments 2 "<epa binary> <source dir>" "$@"
host=127.0.0.1
need mbpoll
need python3
need curl
hb_pid=""
stop_heartbeat() { [ -n "$hb_pid" ] && kill "$hb_pid" 2>/dev/null; [ -n "$hb_pid" ] && wait "$hb_pid" 2>/dev/null; hb_pid=""; }
trap 'stop_heartbeat; cleanup' EXIT

mb() { mbpoll -m tcp -a 1 -p "$port" -0 -1 -o 1 "$@"; }
value_of() { awk -v ref="[$1]:" '$1 == ref { print $2; exit }'; }
near() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a != "" && d <= t) }'; }
written() { grep -q "Written 1 references" <<<"$1"; }
step="setup"
die() { abort "$step: $*"; }

# ---- (1) the map, as an integrator gets it ----
step="(1) map"
"$epa" registers "$src/registers/epa.csv" --csv "$tmp/map.csv" >/dev/null 2>&1 || { echo "FAIL: epa registers --csv" >&2; exit 1; }
addr() {  # addr NAME TABLE [TYPE]: the address, checked: the table, the type, ABCD for 32-bit values
  local row
  row=$(awk -F, -v n="$1" -v t="$2" '$1 == n && $2 == t { print $3 "," $5 "," $6; exit }' "$tmp/map.csv")
  [ -n "$row" ] || { echo "FAIL: (1) map: no point $1 in table $2" >&2; exit 1; }
  IFS=, read -r a ty wo <<<"$row"
  [ -z "${3:-}" ] || [ "$ty" = "$3" ] || { echo "FAIL: (1) map: $1 is $ty, expected $3" >&2; exit 1; }
  case "$ty" in float32|uint32|int32) [ "$wo" = "ABCD" ] || { echo "FAIL: (1) map: $1 word order $wo" >&2; exit 1; } ;; esac
  echo "$a"
}
A_SETPOINT=$(addr setpoint_mm holding float32) || exit 1
A_MODE=$(addr mode holding uint16) || exit 1
A_VALVE=$(addr manual_valve_v holding float32) || exit 1
A_HEARTBEAT=$(addr heartbeat holding uint32) || exit 1
A_UNLOCK=$(addr unlock holding key64) || exit 1
A_CW=$(addr control_word holding uint16) || exit 1
A_SELECT=$(addr record_select holding uint16) || exit 1
A_REC1=$(addr record1_target_mm holding float32) || exit 1
A_POS=$(addr position_mm input float32) || exit 1
A_VERSION=$(addr version_major input uint16) || exit 1
A_STATUS=$(addr status_word input uint16) || exit 1
A_MOVE_END=$(addr move_end input uint16) || exit 1
A_FCODE=$(addr fault_code input uint16) || exit 1
A_FCOUNT=$(addr fault_history_count input uint32) || exit 1
A_F0=$(addr fault_0_code input uint16) || exit 1
pass "(1) map: $(($(wc -l <"$tmp/map.csv") - 1)) points from epa registers --csv; status_word input $A_STATUS, control_word holding $A_CW"

token="IZrXZnw2VNsOO9NPydTejzee"
web_static_dir="$src/web" web_token=$token
start_appliance "$src/registers/epa.csv" "[limits]
soft_max_mm = 300.0
setpoint_max_mm = 290.0
heartbeat_timeout_s = 5.0"
( n=0; while :; do n=$((n + 1)); mb -t 4:int -B -r "$A_HEARTBEAT" "$host" "$n" >/dev/null 2>&1; sleep 0.2; done ) &
hb_pid=$!

position() { mb -t 3:float -B -r "$A_POS" -c 1 "$host" 2>/dev/null | value_of "$A_POS"; }
status() { mb -t 3 -r "$A_STATUS" -c 1 "$host" 2>/dev/null | value_of "$A_STATUS"; }
mode() { mb -t 4 -r "$A_MODE" -c 1 "$host" 2>/dev/null | value_of "$A_MODE"; }
write16() { local out; out=$(mb -t 4 -r "$1" "$host" "$2" 2>&1); written "$out" || die "writing $2 at holding $1: $out"; }
names=(ready run_enabled moving in_position target_reached following_error warning fault_latched ack halted jogging manual_mode off_target)
bits() { local w=$1 i s=""; for i in "${!names[@]}"; do (( w >> i & 1 )) && s+="${names[$i]},"; done; echo "${s%,}"; }
# wait_status SET CLEAR TIMEOUT_MS WHAT: polls until all of SET are set and all of CLEAR clear; sets `waited` (ms) and `word`
wait_status() {
  local t0 deadline
  t0=$(now_ms); deadline=$((t0 + $3))
  while [ "$(now_ms)" -lt "$deadline" ]; do
    word=$(status)
    if [ -n "$word" ] && (( (word & $1) == $1 && (word & $2) == 0 )); then waited=$(( $(now_ms) - t0 )); return 0; fi
    sleep 0.01
  done
  die "$4: status_word did not have $(bits "$1") set and $(bits "$2") clear within $3 ms; last '$(bits "${word:-0}")', position $(position) mm, mode $(mode)"
}
wait_standing() {
  local last now i
  last=$(position)
  for i in $(seq 1 20); do sleep 0.3; now=$(position); near "$now" "$last" 0.2 && { echo "$now"; return 0; }; last=$now; done
  die "$1: the piston did not stand still within 6 s"
}
READY=1 RUN_ENABLED=2 MOVING=4 IN_POSITION=8 TARGET_REACHED=16 FAULT=128 ACK=256 HALTED=512 JOGGING=1024 MANUAL=2048

# ---- (2) version ----
step="(2) version"
out=$(mb -t 3 -r "$A_VERSION" -c 3 "$host" 2>&1)
version="$(value_of "$A_VERSION" <<<"$out").$(value_of $((A_VERSION + 1)) <<<"$out").$(value_of $((A_VERSION + 2)) <<<"$out")"
expected=$("$epa" --version | sed -n 's/^epa //p')
[ "$version" = "$expected" ] && pass "(2) version registers read $version = epa --version (mbpoll cannot send FC43/14: not tested with it)" \
  || fail "(2) version registers read '$version', epa --version says $expected: $out"

# ---- (3) enable ----
step="(3) enable"
t0=$(now_ms)
write16 "$A_MODE" 1
wait_status $((READY | RUN_ENABLED | IN_POSITION)) $MOVING 2000 "mode RUN"
pass "(3) mode 1: ready, run_enabled, in_position after $(( $(now_ms) - t0 )) ms ($(bits "$word"))"

# ---- (4) the unlock is per connection: mbpoll's next call is locked again ----
step="(4) record"
out=$(mb -t 4 -r "$A_UNLOCK" "$host" 24122 39959 53835 2159 2>&1)  # 5e3a 9c17 d24b 086f
grep -q "Written 4 references" <<<"$out" && pass "(4) unlock key written (4 registers, FC16)" || fail "(4) unlock: $out"
out=$(mb -t 4:float -B -r "$A_REC1" "$host" 150 2>&1)
if ! written "$out" && grep -qi "slave device or server failure" <<<"$out"; then
  pass "(4) record1_target_mm in the next mbpoll call (a new connection) is refused with exception 04: records need one connection for unlock and write"
else
  fail "(4) record1_target_mm after an unlock in another connection: expected exception 04, got: $out"
fi
# Record 1 for (5): 250 mm at 40 mm/s under pp-traj (the law made for a profile), so the start in
# (5) is a move of seconds. A start of the target the piston stands at comes into position again
# 0.1 s later, which can be before mbpoll's next read on a loaded machine: target_reached would be
# set again at the ack, and the check that the start clears it would race.
code=$(curl -s -o "$tmp/record.json" -w '%{http_code}' --max-time 5 -X POST -H "Content-Type: application/json" \
  -H "Authorization: Bearer $token" -d '{"record":1,"target_mm":250,"speed_mm_s":40,"window_mm":0,"controller":"pp-traj"}' \
  "${url}api/records")
[ "$code" = 200 ] || die "record 1 over the web API: HTTP $code $(cat "$tmp/record.json")"
out=$(mb -t 4:float -B -r "$A_REC1" -c 2 "$host" 2>&1)
r_target=$(value_of "$A_REC1" <<<"$out"); r_speed=$(value_of $((A_REC1 + 2)) <<<"$out")
near "$r_target" 250 0 && near "$r_speed" 40 0 && pass "(4) record 1 written over the web API reads back in mbpoll: $r_target mm at $r_speed mm/s" \
  || fail "(4) record 1 written over the web API as 250 mm at 40 mm/s, mbpoll reads '$r_target' mm at '$r_speed' mm/s: $out"

# ---- (5) the setpoint (record 0), then the start/ack handshake on record 1 ----
step="(5) start"
write16 "$A_SELECT" 0
t0=$(now_ms)
out=$(mb -t 4:float -B -r "$A_SETPOINT" "$host" 150 2>&1); written "$out" || die "setpoint 150: $out"
wait_status $((IN_POSITION | TARGET_REACHED)) $MOVING 15000 "setpoint 150 (moves at once in RUN)"
pass "(5) setpoint 150 written (-t 4:float -B): in_position + target_reached after $(( $(now_ms) - t0 )) ms at $(position) mm"
write16 "$A_SELECT" 1
t0=$(now_ms)
write16 "$A_CW" 1
wait_status $ACK 0 2000 "ack after start=1"; t_ack=$waited
(( word & MOVING )) || fail "(5) ack without moving (record 1: 150 -> 250 mm at 40 mm/s): $(bits "$word")"
(( word & TARGET_REACHED )) && fail "(5) target_reached still set once the start is acknowledged: $(bits "$word")"
t1=$(now_ms)
write16 "$A_CW" 0
wait_status 0 $ACK 2000 "ack clears after start=0"; t_clear=$waited
wait_status $((IN_POSITION | TARGET_REACHED)) $((MOVING | ACK)) 15000 "in_position + target_reached after the start"
pos=$(position)
near "$pos" 250 1 || fail "(5) in position at $pos mm, expected record 1's 250 +- 1"
pass "(5) start record 1 (150 -> 250 mm at 40 mm/s): ack after ${t_ack} ms, cleared ${t_clear} ms after start=0, in_position + target_reached $(( $(now_ms) - t0 )) ms after start=1 at $pos mm"

# ---- (6) halt a setpoint move ----
step="(6) halt"
out=$(mb -t 4:float -B -r "$A_SETPOINT" "$host" 40 2>&1); written "$out" || die "setpoint 40: $out"
sleep 0.1  # stays, the stimulus: the halt comes 0.1 s into the move
t0=$(now_ms)
write16 "$A_CW" 2
wait_status $HALTED 0 2000 "halted after halt=1"; t_halted=$waited
wait_status $HALTED $((MOVING | IN_POSITION)) 5000 "halted, standing short of the target, not in position"
write16 "$A_CW" 0
rest=$(wait_standing "after the halt")
end=$(mb -t 3 -r "$A_MOVE_END" -c 1 "$host" 2>/dev/null | value_of "$A_MOVE_END")
[ "$end" = "2" ] || fail "(6) move_end after the halt: expected 2 (halted), got '$end'"
[ "$(mode)" = "1" ] || fail "(6) mode after the halt: expected 1 (run)"
near "$rest" 40 3 && fail "(6) the piston went on to the setpoint 40 mm ($rest mm): the halt did not stop it"
pass "(6) halt 0.1 s into 250 -> 40 mm: halted after ${t_halted} ms, standing, not in position, $(( $(now_ms) - t0 )) ms after halt=1 (incl. standing check), standing at $rest mm, move_end $end"

# ---- (7) jog in MANUAL ----
step="(7) jog"
write16 "$A_MODE" 2
wait_status $((MANUAL | READY)) $RUN_ENABLED 2000 "MANUAL"
before=$(wait_standing "before the jog")
t0=$(now_ms)
write16 "$A_CW" 4
wait_status $((JOGGING | MOVING)) 0 2000 "jogging after jog_plus"; t_jog=$waited
while [ $(( $(now_ms) - t0 )) -lt 1500 ]; do sleep 0.3; write16 "$A_CW" 4; done  # the keep-alive
write16 "$A_CW" 0
wait_status $MANUAL $((JOGGING | MOVING)) 2000 "jog released"; t_brake=$waited
after=$(wait_standing "after the jog")
awk -v a="$after" -v b="$before" 'BEGIN { exit !(a - b > 15) }' || fail "(7) jog_plus for 1.5 s: $before -> $after mm, expected > 15 mm up"
pass "(7) jog_plus (control word 4, rewritten every 0.3 s): jogging after ${t_jog} ms, $before -> $after mm in 1.5 s, braked ${t_brake} ms after release"

# ---- (8) fault, reset, fault history ----
step="(8) fault"
count_before=$(mb -t 3:int -B -r "$A_FCOUNT" -c 1 "$host" 2>/dev/null | value_of "$A_FCOUNT")
t0=$(now_ms)
out=$(mb -t 4:float -B -r "$A_VALVE" "$host" 1.5 2>&1); written "$out" || die "manual_valve_v 1.5: $out"
wait_status $FAULT 0 15000 "soft-limit fault"; t_fault=$waited
(( word & READY )) && fail "(8) ready while a fault is latched: $(bits "$word")"
code=$(mb -t 3 -r "$A_FCODE" -c 1 "$host" 2>/dev/null | value_of "$A_FCODE")
[ "$code" = "3" ] && [ "$(mode)" = "3" ] || fail "(8) fault_code '$code' (expected 3), mode $(mode) (expected 3)"
t1=$(now_ms)
write16 "$A_CW" 16
wait_status $READY $FAULT 2000 "ready after the reset bit"; t_reset=$waited
write16 "$A_CW" 0
count_at_ready=$(mb -t 3:int -B -r "$A_FCOUNT" -c 1 "$host" 2>/dev/null | value_of "$A_FCOUNT")
t2=$(now_ms); count=$count_at_ready
while [ "$count" = "$count_before" ] && [ $(( $(now_ms) - t2 )) -lt 2000 ]; do
  sleep 0.005; count=$(mb -t 3:int -B -r "$A_FCOUNT" -c 1 "$host" 2>/dev/null | value_of "$A_FCOUNT")
done
lag=$(( $(now_ms) - t2 ))
[ "$count" = "$((count_before + 1))" ] || fail "(8) fault_history_count $count (waited 2 s), expected $((count_before + 1))"
out=$(mb -t 3 -r "$A_F0" -c 2 "$host" 2>&1)
e_code=$(value_of "$A_F0" <<<"$out"); e_mode=$(value_of $((A_F0 + 1)) <<<"$out")
e_time=$(mb -t 3:int -B -r $((A_F0 + 2)) -c 1 "$host" 2>/dev/null | value_of $((A_F0 + 2)))
out=$(mb -t 3:float -B -r $((A_F0 + 4)) -c 3 "$host" 2>&1)
e_pos=$(value_of $((A_F0 + 4)) <<<"$out"); e_sp=$(value_of $((A_F0 + 6)) <<<"$out"); e_valve=$(value_of $((A_F0 + 8)) <<<"$out")
[ "$e_code" = "3" ] && [ "$e_mode" = "2" ] || fail "(8) newest entry: code '$e_code' mode '$e_mode', expected 3 and 2 (manual)"
near "$e_time" "$(date +%s)" 60 || fail "(8) newest entry: time '$e_time' is not now"
awk -v p="$e_pos" 'BEGIN { exit !(p >= 299 && p <= 310) }' || fail "(8) newest entry: position '$e_pos'"
near "$e_valve" 1.5 0.001 || fail "(8) newest entry: valve '$e_valve', expected 1.5"
pass "(8) soft-limit latched ${t_fault} ms after valve 1.5 V, reset bit -> ready in ${t_reset} ms; count at ready $count_at_ready, $count after ${lag} ms; newest: code $e_code, mode $e_mode, time $e_time, position $e_pos, setpoint $e_sp, valve $e_valve"
[ "$count_at_ready" = "$((count_before + 1))" ] \
  || fail "(8) DEVICE: fault_history_count read right after the reset (status ready, mode 0) was still $count_at_ready; the reset fault was counted ${lag} ms later"

# ---- stop ----
stop_heartbeat
finish_test
