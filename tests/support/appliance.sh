# Shell harness for tests that run the appliance as a process (sourced, not executed): a temp
# folder, PASS/FAIL bookkeeping, a free loopback port, and stopping the appliance by its PID
# (SIGTERM, then SIGKILL after 5 s) on every exit path. The sourcing script sets `pid` when it
# starts the appliance and writes its log to "$tmp/epa.log".
# Usage: source "$(dirname "$0")/../support/appliance.sh" NAME

tmp=$(mktemp -d "${TMPDIR:-/tmp}/epa-$1.XXXXXX")
pid=""
passed=0
failed=0

now_ms() { echo $(( ${EPOCHREALTIME/./} / 1000 )); }

# wait_until MS COMMAND [ARGS...]: runs COMMAND every 50 ms until it succeeds or MS milliseconds
# have passed, and returns whether it succeeded (tried once more at the deadline). A wait for an
# event instead of a fixed sleep; the test then checks what it checked before.
wait_until() {
  local deadline=$(( $(now_ms) + $1 ))
  shift
  while [ "$(now_ms)" -lt "$deadline" ]; do
    "$@" && return 0
    sleep 0.05
  done
  "$@"
}

# Stops the appliance by its PID; returns its exit status.
stop_appliance() {
  [ -n "$pid" ] || return 0
  local status=0
  if kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null
    local deadline=$(( $(now_ms) + 5000 ))
    while kill -0 "$pid" 2>/dev/null && [ "$(now_ms)" -lt "$deadline" ]; do sleep 0.05; done
    if kill -0 "$pid" 2>/dev/null; then
      echo "appliance (pid $pid) ignored SIGTERM for 5 s: SIGKILL" >&2
      kill -KILL "$pid" 2>/dev/null
    fi
  fi
  wait "$pid" 2>/dev/null
  status=$?
  pid=""
  return $status
}
cleanup() {
  stop_appliance
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP

pass() { passed=$((passed + 1)); echo "PASS: $*"; }
fail() {
  failed=$((failed + 1))
  echo "FAIL: $*" >&2
}
show_log() {
  echo "---- appliance log ($tmp/epa.log) ----" >&2
  cat "$tmp/epa.log" >&2
  echo "---- end of log ----" >&2
}
abort() {  # a failure the later checks cannot recover from
  fail "$*"
  show_log
  echo "$passed passed, $failed failed"
  exit 1
}

# finish_test: the appliance, still up, stops on SIGTERM with exit status 0 (a check of its own);
# the log on any failure; "N passed, M failed"; returns 0 only when nothing failed (the script's
# last command, so its exit status).
finish_test() {
  if kill -0 "$pid" 2>/dev/null; then
    stop_appliance
    local status=$?
    if [ $status -eq 0 ]; then pass "appliance stopped on SIGTERM with exit status 0"; else fail "appliance stop: exit status $status after SIGTERM"; fi
  else
    fail "the appliance died during the test"
    pid=""
  fi
  [ "$failed" -eq 0 ] || show_log
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
}

# test_arguments COUNT USAGE "$@": the script's arguments, exactly COUNT of them, else "usage: $0
# USAGE" and exit 2; sets `epa` (checked to be an executable) and `src` from the first two.
test_arguments() {
  local count=$1 usage=$2
  shift 2
  if [ $# -ne "$count" ]; then
    echo "usage: $0 $usage" >&2
    exit 2
  fi
  epa=$1
  src=$2
  [ -x "$epa" ] || { echo "FAIL: $epa is not an executable" >&2; exit 1; }
}

# need PROGRAM [PACKAGE]: PROGRAM on PATH, else FAIL naming the Debian package (default: PROGRAM)
# that scripts/install-deps.sh installs.
need() {
  command -v "$1" >/dev/null || { echo "FAIL: $1 is not installed (package ${2:-$1}: scripts/install-deps.sh installs it)" >&2; exit 1; }
}

free_port() { python3 -c "import socket; s=socket.socket(); s.bind(('127.0.0.1',0)); print(s.getsockname()[1])"; }

unlock_key="5e3a9c17d24b086f"  # [modbus] unlock_key of the test appliances (as tests/support/epa_appliance.py)

# start_appliance MAP [EXTRA_TOML] [SERVE_ARGS...]: starts `epa serve` (simulated plant; SERVE_ARGS
# default to --mode stop) with the register map MAP on a free loopback port, the tests' unlock key
# and the TOML text EXTRA_TOML appended (e.g. a [limits] section); writes "$tmp/epa.toml", appends
# its log to "$tmp/epa.log" and waits (at most 10 s) until it accepts Modbus connections. Sets
# `port` (Modbus) and `pid`. With `web_static_dir` set (and `web_token`, empty: commands off) the
# web server runs too, on a free port, and is waited for by GET /api/status: sets `web_port` and
# `url` (http://127.0.0.1:PORT/). With `web_tls_dir` too (a folder of `epa certs init`), the web
# port speaks HTTPS with its files ([modbus_tls] ca, cert, key, crl): `url` is https://localhost:PORT/
# and `curl_tls` holds curl's --cacert option for it. Aborts when the appliance exits or never answers.
start_appliance() {
  local map=$1 extra=${2:-}
  shift $(( $# < 2 ? $# : 2 ))
  [ $# -gt 0 ] || set -- --mode stop
  port=$(free_port)
  local web="enabled = false" tls_files=""
  curl_tls=()
  if [ -n "${web_static_dir:-}" ]; then
    web_port=$(free_port)
    url="http://127.0.0.1:$web_port/"
    web="address = \"127.0.0.1\"
port = $web_port
static_dir = \"$web_static_dir\"
token = \"${web_token:-}\""
    if [ -n "${web_tls_dir:-}" ]; then
      url="https://localhost:$web_port/"
      curl_tls=(--cacert "$web_tls_dir/ca.pem")
      web="$web
tls = true"
      tls_files="[modbus_tls]
ca = \"$web_tls_dir/ca.pem\"
cert = \"$web_tls_dir/device.pem\"
key = \"$web_tls_dir/device.key\"
crl = \"$web_tls_dir/crl.pem\"
"
    fi
  fi
  cat >"$tmp/epa.toml" <<CONFIG
# written by tests/support/appliance.sh
[modbus]
address = "127.0.0.1"
port = $port
register_map = "$map"
unlock_key = "$unlock_key"

$tls_files[web]
$web

[log]
status_interval_s = 0

[recorder]
directory = "$tmp/runs"
$extra
CONFIG
  "$epa" serve --config "$tmp/epa.toml" --db "$tmp/epa.db" "$@" >>"$tmp/epa.log" 2>&1 &
  pid=$!
  echo "appliance pid $pid: modbus 127.0.0.1:$port${web_port:+, web ${url:-}} (config $tmp/epa.toml)"
  local deadline=$(( $(now_ms) + 10000 ))
  while [ "$(now_ms)" -lt "$deadline" ]; do
    kill -0 "$pid" 2>/dev/null || abort "the appliance exited during start-up"
    if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      [ -z "${web_static_dir:-}" ] && return 0
      curl -s --max-time 2 "${curl_tls[@]}" "${url}api/status" 2>/dev/null | grep -q '"mode"' && return 0
    fi
    sleep 0.05
  done
  abort "the appliance did not answer on 127.0.0.1:$port${web_port:+ and $url} within 10 s"
}
