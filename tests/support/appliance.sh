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

free_port() { python3 -c "import socket; s=socket.socket(); s.bind(('127.0.0.1',0)); print(s.getsockname()[1])"; }

unlock_key="5e3a9c17d24b086f"  # [modbus] unlock_key of the test appliances (as tests/support/epa_appliance.py)

# Starts `epa serve` (mode STOP, simulated plant) on a free loopback port: writes "$tmp/epa.toml"
# with the register map $1, the tests' unlock key, no web server, and the TOML text $2 appended
# (e.g. a [limits] section), logs to "$tmp/epa.log", and waits (at most 10 s) until it accepts TCP
# connections. Sets `port` and `pid`; aborts when it exits or never listens.
start_appliance() {
  local map=$1 extra=${2:-}
  port=$(free_port)
  cat >"$tmp/epa.toml" <<CONFIG
# written by tests/support/appliance.sh
[modbus]
address = "127.0.0.1"
port = $port
register_map = "$map"
unlock_key = "$unlock_key"

[web]
enabled = false

[log]
status_interval_s = 0

[recorder]
directory = "$tmp/runs"
$extra
CONFIG
  "$epa" serve --config "$tmp/epa.toml" --db "$tmp/epa.db" --mode stop >"$tmp/epa.log" 2>&1 &
  pid=$!
  echo "appliance pid $pid on 127.0.0.1:$port (config $tmp/epa.toml)"
  local deadline=$(( $(now_ms) + 10000 ))
  while [ "$(now_ms)" -lt "$deadline" ]; do
    kill -0 "$pid" 2>/dev/null || abort "the appliance exited during start-up"
    if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then return 0; fi
    sleep 0.05
  done
  abort "the appliance did not accept connections on 127.0.0.1:$port within 10 s"
}
