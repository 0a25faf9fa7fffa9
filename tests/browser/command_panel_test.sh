#!/usr/bin/env bash
# The page's command panel and position-record table in a real browser: Debian's headless
# Chromium drives the panel through its DOM (a probe script, tests/browser/command_probe.js, added
# to a copy of the page, types the token, clicks, presses and releases the jog buttons), and every
# effect is checked through the appliance's own API with curl, never through the page's state.
#
#   command_panel_test.sh <epa binary> <source dir> <artifacts dir>
#
# (1) Without a [web] token: the panel is not shown, the record table is, without edit buttons,
#     and POST /api/points and /api/records answer 403.
# With a token (the simulated plant, RUN at 50 mm):
# (2) a wrong token in the panel: the page shows the server's 401 text; nothing changed;
# (3) record 3 edited in its row: /api/records has the new values, the audit names the web;
# (4) a start from STOP is refused with the server's 409 text; RUN, record 3, start: the piston
#     arrives within 1 mm of record 3's target, and the status-bits card shows in_position lit;
# (5) a halt during a slow move (record 4): the piston stops short of the target and stays;
# (6) MANUAL, jog + held for 2.5 s: the piston moves up further than one keep-alive period
#     allows, stops after the release; jog - the other way;
# (7) a soft-limit fault (manual valve over the API) is cleared by the panel's reset;
# (8) a screenshot of the panel at 1280 and 390 px to <artifacts dir>.
# Loopback only, bounded waits; the appliance is stopped by its PID.
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" command-panel
test_arguments 3 "<epa binary> <source dir> <artifacts dir>" "$@"
artifacts=$3
token="X8DGaf4hnkECJ9wmbmrjCJ8M"
need chromium
need curl
mkdir -p "$artifacts"
source "$(dirname "$0")/../support/chromium.sh"
BROWSER_TIMEOUT_S=90

# The page as shipped plus the probe.
mkdir -p "$tmp/web"
cp -r "$src/web/." "$tmp/web/"
cp "$(dirname "$0")/command_probe.js" "$tmp/web/"
sed -i 's|</body>|<script src="/command_probe.js"></script>\n</body>|' "$tmp/web/index.html"
grep -q command_probe.js "$tmp/web/index.html" || abort "could not add the probe to the page's copy"

# ---- the appliance ----
start() {  # start <token or "">: a fresh store each time
  rm -f "$tmp/epa.db"
  web_static_dir="$tmp/web" web_token=$1
  start_appliance "$src/registers/epa.csv" "[limits]
soft_max_mm = 450
setpoint_max_mm = 440" --mode run --setpoint 50
}

api() { curl -s --max-time 2 "${url%/}$1" 2>/dev/null; }
# One value of the appliance's JSON: jq-less, by python (the page's JSON is the server's).
status_value() { api /api/status | python3 -c "import json,sys; d=json.load(sys.stdin); v=d$1; print(str(v).lower() if isinstance(v,bool) else v)"; }
position() { status_value '["position_mm"]'; }
record_value() { api /api/records | python3 -c "import json,sys; print(json.load(sys.stdin)['records'][$1 - 1]['$2'])"; }
post_status() {  # post_status <path> <body> [token]: the HTTP status
  curl -s -o /dev/null -w '%{http_code}' --max-time 2 -X POST -H "Content-Type: application/json" \
    ${3:+-H "Authorization: Bearer $3"} -d "$2" "${url%/}$1"
}
# waits up to <s> for `status_value <path>` to satisfy the awk test on v; prints the last value
wait_status() {  # wait_status <seconds> <python path> <awk condition on v>
  local deadline=$(( $(now_ms) + $1 * 1000 )) v=""
  while [ "$(now_ms)" -lt "$deadline" ]; do
    v=$(status_value "$2")
    awk -v v="$v" "BEGIN { exit !($3) }" && { echo "$v"; return 0; }
    sleep 0.1
  done
  echo "$v"
  return 1
}
near() { awk -v a="$1" -v b="$2" -v d="$3" 'BEGIN { x = a - b; if (x < 0) x = -x; exit !(a != "" && x <= d) }'; }

# The panel driven by the probe through the steps given ("token=...;mode=run;..."), the DOM after
# it; <budget> is Chromium's virtual time, which runs well ahead of real time. The probe stops the
# page's timers when it has reported, so the budget only bounds a probe that hangs: it is longer
# than the probe's own waits (10 s each), which report what they waited for.
# A Chromium that exits without a page (no <body> on stdout: it crashed or was killed) has not run
# the probe at all, so nothing was clicked: it is started once more, and that is said.
probe() {  # probe <steps> [budget_ms]
  local t0=$(now_ms) dom attempt
  for attempt in 1 2; do
    dom=$(browser --virtual-time-budget="${2:-60000}" --window-size=1280,900 --dump-dom "$url#$1")
    echo "probe '${1//$token/TOKEN}': $(( $(now_ms) - t0 )) ms" >&2
    grep -q "<body" <<<"$dom" && break
    echo "probe: Chromium gave no page (${#dom} bytes of output); the end of its log:" >&2
    tail -n 5 "$tmp/chromium.log" >&2
    [ "$attempt" = 1 ] && echo "probe: once more" >&2
  done
  printf '%s\n' "$dom"
}
probe_ok() {  # probe_ok <label> <dom>: the probe finished its steps
  local state
  state=$(body_attr data-probe <<<"$2")
  [ "$state" = done ] && return 0
  fail "$1: the probe did not finish: '${state:-no report}' (answers: $(body_attr data-answers <<<"$2"); ${#2} bytes of DOM)"
  tail -n 5 "$tmp/chromium.log" >&2
  return 1
}

# ---- (1) without a token: no panel, a read-only table, commands 403 ----
start ""
dom=$(probe "")
probe_ok "(1)" "$dom"
panel=$(body_attr data-panel <<<"$dom")
[ "$panel" = hidden ] && pass "(1) without a [web] token the command panel is not shown" \
  || fail "(1) data-panel: expected 'hidden' without a token, got '$panel'"
grep -q '<section class="card span2" id="command" hidden' <<<"$dom" && pass "(1) the panel's section carries hidden" \
  || fail "(1) the command panel's section is not hidden in the DOM"
rows=$(grep -o '<tr data-record="[0-9]*"' <<<"$dom" | wc -l)
edits=$(grep -c 'class="rec-edit"' <<<"$dom")
[ "$rows" -eq 32 ] && [ "$edits" -eq 0 ] && pass "(1) the record table shows 32 rows, read-only (no edit buttons)" \
  || fail "(1) record table: expected 32 rows and no edit buttons, got $rows rows, $edits edit buttons"
for path in /api/points /api/records; do
  code=$(post_status "$path" '{"record":3,"target_mm":100}' anything)
  [ "$code" = 403 ] && pass "(1) POST $path without a configured token: 403" || fail "(1) POST $path without a configured token: expected 403, got $code"
done
stop_appliance

# ---- with a token ----
start "$token"
wait_status 10 '["position_mm"]' 'v > 49 && v < 51' >/dev/null || true  # the piston settles at 50 mm (bounded)

# (2) a wrong token: the server's 401 text on the page, nothing changed
dom=$(probe "token=wrong-token;edit=3,200,0,1.5,pp-traj")
probe_ok "(2)" "$dom" && {
  answer=$(grep -o 'id="rec-answer"[^>]*>[^<]*' <<<"$dom" | sed 's/.*>//')
  if [[ $answer == *"refused (401): missing or wrong token"* ]]; then pass "(2) a wrong token: the page shows '$answer'"
  else fail "(2) a wrong token: expected the server's 401 text in #rec-answer, got '$answer'"; fi
}
t=$(record_value 3 target_mm)
[ "$t" = "0.0" ] && pass "(2) record 3 unchanged after the wrong token" || fail "(2) record 3 target after a wrong token: expected 0.0, got $t"

# (3) record 3 edited in its row
dom=$(probe "token=$token;edit=3,200,0,1.5,pp-traj")
probe_ok "(3)" "$dom"
t=$(record_value 3 target_mm); w=$(record_value 3 window_mm); c=$(record_value 3 controller)
[ "$t" = "200.0" ] && [ "$w" = "1.5" ] && [ "$c" = pp-traj ] && pass "(3) /api/records: record 3 = 200 mm, window 1.5 mm, law pp-traj" \
  || fail "(3) /api/records record 3: expected 200.0 / 1.5 / pp-traj, got $t / $w / $c"
api /api/audit | grep -q '"point":"record3_target_mm","source":"web 127.0.0.1"' && pass "(3) the audit trail has the web's record3_target_mm" \
  || fail "(3) /api/audit does not show record3_target_mm from the web"

# (4) start: refused from STOP with the server's text; from RUN the piston arrives
dom=$(probe "token=$token;mode=stop;start=3")
probe_ok "(4)" "$dom" && {
  answers=$(body_attr data-answers <<<"$dom")
  if [[ $answers == *"start record 3: refused (409):"*"a start needs mode RUN"* ]]; then pass "(4) a start from STOP: the page shows the server's 409 text"
  else fail "(4) a start from STOP: expected 'refused (409): ... a start needs mode RUN' on the page, got '$answers'"; fi
}
dom=$(probe "token=$token;mode=run;start=3")
probe_ok "(4)" "$dom"
t0=$(now_ms)
# Arrived: the move's target_reached (in record 3's window for in_position_time_s), then settled.
if wait_status 15 '["status_bits"]["target_reached"]' 'v == "true"' >/dev/null; then
  arrived_ms=$(( $(now_ms) - t0 ))
  sleep 0.5  # stays: the settling time the check below judges (still within 1 mm after it)
  pos=$(position)
  near "$pos" 200 1 && pass "(4) RUN, record 3, start: target_reached after $arrived_ms ms, settled at $pos mm (target 200, within 1 mm)" \
    || fail "(4) record 3 (200 mm) reached its window, but settled at $pos mm: not within 1 mm"
  [ "$(status_value '["status_bits"]["in_position"]')" = true ] && pass "(4) /api/status: in_position" \
    || fail "(4) /api/status: in_position not set after the arrival"
else
  fail "(4) record 3 (200 mm) started, but target_reached is not set after 15 s (position $(position) mm)"
fi
dom=$(browser --virtual-time-budget=3000 --window-size=1280,900 --dump-dom "$url")
lamp=$(grep -o '<li id="sb-in_position"[^>]*>' <<<"$dom")
if [[ $lamp == *'class="lamp on"'* && $lamp == *'data-on="1"'* ]]; then pass "(4) the status-bits card shows in_position lit: $lamp"
else fail "(4) the in_position lamp is not lit after the arrival: '$lamp'"; fi
word=$(grep -o 'id="sb-word"[^>]*>[^<]*' <<<"$dom" | sed 's/.*>//')
expected=$(printf '0x%04X' "$(status_value '["status_word"]')")
[ "$word" = "$expected" ] && pass "(4) the card shows status_word $word, as /api/status" || fail "(4) the card's word '$word', /api/status $expected"

# (5) a halt during a slow move. Record 4 names pp-traj: a record's law runs its own move only, so
# "running" would be the selected pp-ffidz, whose readings on the paper's printed model swing too
# far for a halt to be judged to 0.5 mm (README, Halt).
dom=$(probe "token=$token;edit=4,420,15,0,pp-traj;start=4")
probe_ok "(5)" "$dom"
if moving=$(wait_status 10 '["position_mm"]' 'v > 203'); then
  dom=$(probe "token=$token;halt")
  probe_ok "(5)" "$dom"
  sleep 1  # stays, as the 1 s between p1 and p2: a halted piston is judged still over time
  p1=$(position); sleep 1; p2=$(position)
  halted=$(status_value '["status_bits"]["halted"]')
  if near "$p1" "$p2" 0.5 && awk -v p="$p2" 'BEGIN { exit !(p < 400) }' && [ "$halted" = true ]; then
    pass "(5) halt during the move to 420 mm (seen at $moving mm): stopped at $p2 mm (1 s later $p1 -> $p2), halted bit set"
  else
    fail "(5) after the halt: position $p1 then $p2 mm (target 420), halted=$halted: expected it to stay put short of 420"
  fi
else
  fail "(5) record 4 (420 mm at 15 mm/s) did not start moving from 200 mm: position $moving"
fi

# (6) jog in MANUAL, press and hold
dom=$(probe "token=$token;mode=manual")
probe_ok "(6)" "$dom"
wait_status 3 '["mode"]' 'v == "manual"' >/dev/null || fail "(6) the panel's Manual button did not set MANUAL"
jog() {  # jog <plus|minus> <sign>
  local before after p1 p2 jogging
  before=$(position)
  dom=$(probe "token=$token;jog=$1,2.5" 60000)
  probe_ok "(6) jog $1" "$dom" || return
  sleep 0.5  # stays, as the 1 s between p1 and p2: a released jog is judged still over time
  p1=$(position); sleep 1; p2=$(position)
  jogging=$(status_value '["status_bits"]["jogging"]')
  # 2.5 s at jog_speed 20 mm/s is ~50 mm; without the keep-alive the jog brakes after 1 s (<= ~21 mm).
  if awk -v a="$before" -v b="$p1" -v s="$2" 'BEGIN { exit !(s * (b - a) > 30) }'; then
    pass "(6) jog $1 held 2.5 s: $before -> $p1 mm (the keep-alive held it beyond 1 s)"
  else
    fail "(6) jog $1 held 2.5 s: $before -> $p1 mm: expected more than 30 mm the $1 way"
  fi
  if near "$p1" "$p2" 0.5 && [ "$jogging" = false ]; then pass "(6) jog $1 released: stopped ($p1 -> $p2 mm over 1 s), jogging bit clear"
  else fail "(6) jog $1 released: position $p1 -> $p2 mm over 1 s, jogging=$jogging: expected it stopped"; fi
}
jog plus 1
jog minus -1

# (7) a fault, reset from the panel
code=$(post_status /api/points '{"manual_valve_v": 1.5}' "$token")
[ "$code" = 200 ] || fail "(7) writing manual_valve_v 1.5 over the API: HTTP $code"
if wait_status 20 '["mode"]' 'v == "fault"' >/dev/null; then
  fault=$(status_value '["fault"]')
  dom=$(probe "token=$token;reset")
  probe_ok "(7)" "$dom"
  mode=$(wait_status 3 '["mode"]' 'v == "stop"')
  [ "$mode" = stop ] && [ "$(status_value '["status_bits"]["fault_latched"]')" = false ] \
    && pass "(7) the panel's reset cleared the $fault fault: mode stop, fault_latched clear" \
    || fail "(7) after the panel's reset: mode $mode, expected stop with no fault latched"
else
  fail "(7) no fault within 20 s of manual_valve_v 1.5 in MANUAL (position $(position) mm)"
fi

# (8) screenshots with the panel shown
rm -f "$artifacts/command_panel.png" "$artifacts/command_panel_phone.png"
browser --virtual-time-budget=3000 --window-size=1280,1400 --screenshot="$artifacts/command_panel.png" "$url" >/dev/null
browser --virtual-time-budget=3000 --window-size=390,1600 --screenshot="$artifacts/command_panel_phone.png" "$url" >/dev/null
for f in command_panel.png command_panel_phone.png; do
  [ -s "$artifacts/$f" ] && pass "(8) screenshot $artifacts/$f" || fail "(8) no screenshot $artifacts/$f"
done

kill -0 "$pid" 2>/dev/null && pass "the appliance is still running" || fail "the appliance died during the test"
stop_appliance
[ "$failed" -eq 0 ] || show_log
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
