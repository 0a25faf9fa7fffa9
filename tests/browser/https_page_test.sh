#!/usr/bin/env bash
# The status page over HTTPS in a real browser: Debian's headless Chromium against a running
# appliance whose web port speaks HTTPS only ([web] tls = true, the files of `epa certs init`).
#
#   https_page_test.sh <epa binary> <source dir> <artifacts dir>
#
# Chromium trusts the plant's CA (ca.pem of `epa certs init`) as a user's browser does once the CA
# is imported: in the NSS database of its user ($HOME/.pki/nssdb, made with certutil in a home of
# the test's own). (1) With a home whose database does not hold the CA, Chromium refuses the
# certificate and the page never runs; (2) with the CA trusted, https://localhost:PORT/ shows live
# status: trend points and the position at the setpoint (50 mm); (3) a setpoint of 150 mm sent
# over HTTPS with the token (curl, the CA trusted) shows up as a position that rose by more than
# 50 mm; (4) a screenshot to <artifacts dir>. The appliance is stopped by its PID.
set -uo pipefail

source "$(dirname "$0")/../support/appliance.sh" https-page
test_arguments 3 "<epa binary> <source dir> <artifacts dir>" "$@"
artifacts=$3
token="Zt4kPq9WmXc2LvB7nR5sHy8J"
need chromium
need curl
need openssl
need certutil
mkdir -p "$artifacts"
source "$(dirname "$0")/../support/chromium.sh"

# ---- the certificates, and a browser user who trusts the CA ----
"$epa" certs init "$tmp/pki" >/dev/null || abort "epa certs init $tmp/pki failed"
trusting_home=$tmp/trusting-home untrusting_home=$tmp/untrusting-home
mkdir -p "$trusting_home/.pki/nssdb" "$untrusting_home/.pki/nssdb"
for home in "$trusting_home" "$untrusting_home"; do
  certutil -d "sql:$home/.pki/nssdb" -N --empty-password || abort "certutil: cannot make an NSS database in $home"
done
certutil -d "sql:$trusting_home/.pki/nssdb" -A -n "epa test CA" -t "C,," -i "$tmp/pki/ca.pem" || abort "certutil: cannot import the CA"

# ---- the appliance: HTTPS only on its web port ----
web_static_dir="$src/web" web_tls_dir="$tmp/pki" web_token=$token
start_appliance "$src/registers/epa.csv" "[limits]
setpoint_max_mm = 300" --mode run --setpoint 50
api() { curl -s --max-time 2 "${curl_tls[@]}" "${url%/}$1" 2>/dev/null; }
status_field() { api /api/status | grep -o "\"$1\":[^,}]*" | head -1 | sed 's/.*://; s/"//g'; }
at_50() { awk -v p="$(status_field position_mm)" 'BEGIN { exit !(p != "" && p > 48 && p < 52) }'; }
wait_until 10000 at_50 || true  # the trend then has a story to show ((2) judges the page)

# The page after 3 s of its own polling (virtual time: chromium runs the timers and fetches), as
# the user of the home $1 sees it.
dump_dom() { HOME=$1 browser --virtual-time-budget=3000 --dump-dom "$url"; }

# ---- (1) not trusted: no page ----
dom=$(dump_dom "$untrusting_home")
if [ -z "$(body_attr data-trend-points <<<"$dom")" ] && ! grep -q 'id="position-chart"' <<<"$dom"; then
  pass "(1) without the CA trusted, Chromium does not show the page"
else
  fail "(1) Chromium showed the page over HTTPS without the CA trusted"
fi

# ---- (2) trusted: live status ----
dom=$(dump_dom "$trusting_home")
points=$(body_attr data-trend-points <<<"$dom")
pos1=$(body_attr data-position-mm <<<"$dom")
if [ -n "$points" ] && [ "$points" -gt 0 ] 2>/dev/null; then
  pass "(2) over HTTPS the page drew $points trend points"
else
  fail "(2) data-trend-points: expected > 0, got '${points}' (chromium log: $(tail -3 "$tmp/chromium.log" 2>/dev/null))"
fi
if awk -v p="$pos1" 'BEGIN { exit !(p != "" && p > 40 && p < 60) }'; then
  pass "(2) over HTTPS the page shows position $pos1 mm (setpoint 50)"
else
  fail "(2) data-position-mm: expected about 50, got '${pos1}'"
fi

# ---- (3) a setpoint over HTTPS moves the position shown ----
code=$(curl -s -o /dev/null -w '%{http_code}' --max-time 2 "${curl_tls[@]}" -X POST -H "Content-Type: application/json" \
  -H "Authorization: Bearer $token" -d '{"setpoint_mm":150}' "${url}api/setpoint")
[ "$code" = 200 ] || fail "(3) POST /api/setpoint over HTTPS with the token: HTTP $code"
pos2=""
deadline=$(( $(now_ms) + 20000 ))
while [ "$(now_ms)" -lt "$deadline" ]; do
  sleep 1  # the pacing of the poll: each look is a Chromium run
  pos2=$(dump_dom "$trusting_home" | body_attr data-position-mm)
  awk -v a="$pos1" -v b="$pos2" 'BEGIN { exit !(b != "" && b - a > 50) }' && break
done
if awk -v a="$pos1" -v b="$pos2" 'BEGIN { exit !(b != "" && b - a > 50) }'; then
  pass "(3) after setpoint 150 over HTTPS the page shows $pos2 mm (was $pos1)"
else
  fail "(3) after setpoint 150 over HTTPS: expected the shown position to rise by > 50 mm from $pos1, got '${pos2}'"
fi

# ---- (4) a screenshot ----
rm -f "$artifacts/status_page_https.png"
HOME=$trusting_home browser --virtual-time-budget=3000 --window-size=1280,900 --screenshot="$artifacts/status_page_https.png" "$url" >/dev/null
if [ -s "$artifacts/status_page_https.png" ]; then pass "(4) screenshot $artifacts/status_page_https.png"; else fail "(4) no screenshot"; fi

finish_test
