#!/usr/bin/env bash
# The status page in a real browser: Debian's headless Chromium against a running appliance on
# the simulated plant, as the commissioning engineer's laptop would open it.
#
#   status_page_test.sh <epa binary> <source dir> <artifacts dir>
#
# Starts `epa serve` (sim, RUN, setpoint 50 mm; Modbus and web on free loopback ports; the page
# from <source dir>/web), waits for it by polling, then: (1) the page's DOM, after its scripts ran,
# has trend points and shows a position; (2) a setpoint of 150 mm written over Modbus (mbpoll)
# shows up as a position that changed by more than 50 mm; (3) a soft-limit fault caused over
# Modbus (MANUAL, 1.5 V up past [limits] soft_max_mm = 300) and reset at once over Modbus appears
# in the Fault history card with its mode; (4) screenshots at laptop (1280x900) and phone
# (390x844) size go to <artifacts dir>; (5) at 1280x800 the recent-moves table, with its rows
# and with the widest rows it can show, fits inside its card and the card inside the window (a
# probe script, added to a copy of the page for this test only, measures it); (6) the footer shows
# the version `epa --version` prints. The appliance is stopped by its PID.
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" browser
test_arguments 3 "<epa binary> <source dir> <artifacts dir>" "$@"
artifacts=$3
host=127.0.0.1
need chromium
need mbpoll
command -v curl >/dev/null || command -v python3 >/dev/null || { echo "FAIL: need curl or python3" >&2; exit 1; }
mkdir -p "$artifacts"
source "$(dirname "$0")/../support/chromium.sh"

http_get() { curl -s --max-time 2 "$1" 2>/dev/null; }

# The page after 3 s of its own polling (virtual time: chromium runs the timers and fetches).
dump_dom() { browser --virtual-time-budget=3000 --dump-dom "$url"; }

# The page as shipped plus a layout probe: after the page's first polls it measures the
# recent-moves table with its rows, then with the widest rows the page can write ("never",
# pp-ngidz, 3-digit positions, a 5-digit move number), and writes both to <body> for --dump-dom:
# "table right, card content right, scroll overflow, viewport width, rows" in CSS pixels.
mkdir -p "$tmp/web"
cp -r "$src/web/." "$tmp/web/"
cat >"$tmp/web/layout_probe.js" <<'EOF3'
"use strict";
setTimeout(() => {
  const table = document.getElementById("moves"), box = table.parentElement, card = table.closest(".card");
  const measure = () => {
    const t = table.getBoundingClientRect(), c = card.getBoundingClientRect(), cs = getComputedStyle(card);
    const content_right = c.right - parseFloat(cs.paddingRight) - parseFloat(cs.borderRightWidth);
    return [t.right, content_right, box.scrollWidth - box.clientWidth, document.documentElement.clientWidth,
            table.tBodies[0].rows.length].map((v) => Math.round(v * 10) / 10).join(" ");
  };
  document.body.dataset.movesReal = measure();
  const rows = table.tBodies[0].innerHTML;
  const widest = "<tr><td>12345</td><td>500 → 500</td><td>pp-ngidz</td><td>never</td><td>never</td><td>123.45</td><td>999.9</td></tr>";
  table.tBodies[0].innerHTML = widest.repeat(3);
  document.body.dataset.movesWidest = measure();
  table.tBodies[0].innerHTML = rows;
}, 2500);
EOF3
sed -i 's|</body>|<script src="/layout_probe.js"></script>\n</body>|' "$tmp/web/index.html"
grep -q layout_probe.js "$tmp/web/index.html" || abort "could not add the layout probe to the page's copy"

# ---- start the appliance ----
web_static_dir="$tmp/web"
start_appliance "$src/registers/epa.csv" "[limits]
soft_max_mm = 300
setpoint_max_mm = 300" --mode run --setpoint 50
modbus_port=$port

# Let the piston reach 50 mm so that the trend has a story to show (bounded; (1) judges the page).
status_field() { http_get "${url}api/status" | grep -o "\"$1\":[^,}]*" | head -1 | sed 's/.*://; s/"//g'; }
at_50() { awk -v p="$(status_field position_mm)" 'BEGIN { exit !(p != "" && p > 48 && p < 52) }'; }
wait_until 10000 at_50 || true

# ---- (1) the page draws the trend and shows the position ----
dom=$(dump_dom)
points=$(body_attr data-trend-points <<<"$dom")
pos1=$(body_attr data-position-mm <<<"$dom")
if [ -n "$points" ] && [ "$points" -gt 0 ] 2>/dev/null; then
  pass "(1) the page drew $points trend points"
else
  fail "(1) data-trend-points: expected > 0, got '${points}'"
fi
if awk -v p="$pos1" 'BEGIN { exit !(p != "" && p > 40 && p < 60) }'; then
  pass "(1) the page shows position $pos1 mm (setpoint 50)"
else
  fail "(1) data-position-mm: expected about 50, got '${pos1}'"
fi
grep -q 'id="position-chart"' <<<"$dom" && grep -q '<canvas' <<<"$dom" || fail "(1) the chart canvas is missing from the page"

# ---- (2) a setpoint written over Modbus moves the position shown ----
out=$(mbpoll -m tcp -a 1 -p "$modbus_port" -0 -1 -o 1 -t 4:float -B -r 0 "$host" 150 2>&1)
grep -q "Written 1 references" <<<"$out" || fail "(2) writing setpoint 150 over Modbus: $out"
pos2=""
deadline=$(( $(now_ms) + 20000 ))
while [ "$(now_ms)" -lt "$deadline" ]; do
  sleep 1
  pos2=$(dump_dom | body_attr data-position-mm)
  awk -v a="$pos1" -v b="$pos2" 'BEGIN { exit !(b != "" && b - a > 50) }' && break
done
if awk -v a="$pos1" -v b="$pos2" 'BEGIN { exit !(b != "" && b - a > 50) }'; then
  pass "(2) after setpoint 150 over Modbus the page shows $pos2 mm (was $pos1)"
else
  fail "(2) after setpoint 150 over Modbus: expected the shown position to rise by > 50 mm from $pos1, got '${pos2}'"
fi
http_get "${url}api/audit" | grep -q '"point":"setpoint_mm"' && pass "(2) the Modbus write is in /api/audit" \
  || fail "(2) /api/audit does not show the Modbus setpoint write"
saved=$(dump_dom | grep -o 'id="s-store">[^<]*' | sed 's/.*>//')
if [[ $saved =~ ^([0-9]+)\ /\ ([0-9]+)$ ]] && [ "${BASH_REMATCH[1]}" -ge 1 ] && [ "${BASH_REMATCH[1]}" = "${BASH_REMATCH[2]}" ]; then
  pass "(2) the page shows the write saved: $saved"
else
  fail "(2) id=s-store: expected 'N / N' with N >= 1 (the Modbus write on disk), got '$saved'"
fi
dump_dom | grep -q 'id="s-tuning-set">paper<' && pass "(2) the page names the tuning set 'paper'" \
  || fail "(2) id=s-tuning-set does not name the tuning set 'paper'"

# ---- (3) a fault caused and reset shows in the Fault history card ----
grep -q 'id="fault-history" data-count="0"' <<<"$(dump_dom)" && pass "(3) the Fault history card is empty at first" \
  || fail "(3) the Fault history card should read data-count=\"0\" before any fault"
out=$(mbpoll -m tcp -a 1 -p "$modbus_port" -0 -1 -o 1 -r 2 "$host" 2 2>&1)  # mode 2: MANUAL
grep -q "Written 1 references" <<<"$out" || fail "(3) writing mode 2 (MANUAL) over Modbus: $out"
in_manual() { [ "$(status_field mode)" = manual ]; }
wait_until 5000 in_manual || true  # the scan cycle has taken the mode (the fault check below judges)
out=$(mbpoll -m tcp -a 1 -p "$modbus_port" -0 -1 -o 1 -t 4:float -B -r 4 "$host" 1.5 2>&1)  # manual_valve_v: up towards 300 mm
grep -q "Written 1 references" <<<"$out" || fail "(3) writing manual_valve_v 1.5 over Modbus: $out"
faulted=0
deadline=$(( $(now_ms) + 15000 ))
while [ "$(now_ms)" -lt "$deadline" ]; do
  if http_get "${url}api/status" | grep -q '"mode":"fault"'; then faulted=1; break; fi
  sleep 0.05
done
out=$(mbpoll -m tcp -a 1 -p "$modbus_port" -0 -1 -o 1 -t 0 -r 0 "$host" 1 2>&1)  # reset (coil 0)
if [ "$faulted" -eq 1 ] && grep -q "Written 1 references" <<<"$out"; then
  pass "(3) soft-limit fault caused in MANUAL and reset over Modbus"
else
  fail "(3) no soft-limit fault within 15 s, or the reset failed: $out"
fi
card=""
deadline=$(( $(now_ms) + 10000 ))
while [ "$(now_ms)" -lt "$deadline" ]; do
  dom=$(dump_dom)
  card=$(sed -n '/id="fault-history"/,/<\/section>/p' <<<"$dom")
  grep -q '<td class="fh-name">soft-limit</td><td>manual</td>' <<<"$card" && break
  sleep 0.5
done
if grep -q '<td class="fh-name">soft-limit</td><td>manual</td>' <<<"$card" && grep -q 'data-count="1"' <<<"$card" \
   && grep -q 'the piston left the soft limits' <<<"$card"; then
  pass "(3) the Fault history card lists the reset fault: soft-limit, in manual, with its cause"
else
  fail "(3) the Fault history card does not list soft-limit in manual after the reset: $card"
fi
http_get "${url}api/status" | grep -q '"mode":"stop"' && pass "(3) the appliance is in STOP after the reset" \
  || fail "(3) the appliance is not in STOP after the reset"

# ---- (4) screenshots ----
rm -f "$artifacts/status_page.png" "$artifacts/status_page_phone.png"
browser --virtual-time-budget=3000 --window-size=1280,900 --screenshot="$artifacts/status_page.png" "$url" >/dev/null
browser --virtual-time-budget=3000 --window-size=390,844 --screenshot="$artifacts/status_page_phone.png" "$url" >/dev/null
for f in status_page.png status_page_phone.png; do
  if [ -s "$artifacts/$f" ]; then pass "(4) screenshot $artifacts/$f"; else fail "(4) no screenshot $artifacts/$f"; fi
done

# ---- (4) at 1280x800 the recent-moves table fits its card, the card the window ----
dom=$(browser --virtual-time-budget=3000 --window-size=1280,800 --dump-dom "$url")
for what in real widest; do
  read -r table_right card_right overflow viewport rows <<<"$(body_attr "data-moves-$what" <<<"$dom")"
  if [ -z "${rows:-}" ]; then
    fail "(4) the layout probe wrote no data-moves-$what (did the page load?)"
  elif [ "$what" = real ] && [ "$rows" -lt 2 ]; then
    fail "(4) the recent-moves table shows $rows rows, expected the two moves of this test"
  elif awk -v t="$table_right" -v c="$card_right" -v o="$overflow" -v v="$viewport" 'BEGIN { exit !(t <= c + 0.5 && o <= 0 && c <= v && v == 1280) }'; then
    pass "(4) 1280x800, $what rows ($rows): table right edge $table_right px <= card content $card_right px <= window $viewport px, no scrolling"
  else
    fail "(4) 1280x800, $what rows ($rows): table right edge $table_right px, card content right $card_right px, scroll overflow $overflow px, window $viewport px: the table is cut off"
  fi
done

# ---- (5) the footer shows the version epa --version prints ----
version=$("$epa" --version | sed -n 's/^epa //p')
shown=$(grep -o 'id="version">[^<]*' <<<"$dom" | sed 's/.*>//')
if [ -n "$version" ] && [ "$shown" = "$version" ]; then
  pass "(5) the page's footer shows version $shown, as epa --version"
else
  fail "(5) footer id=version: expected '$version' (epa --version), got '$shown'"
fi

kill -0 "$pid" 2>/dev/null && pass "the appliance is still running" || fail "the appliance died during the test"
stop_appliance
[ "$failed" -eq 0 ] || show_log
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
