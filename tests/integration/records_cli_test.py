#!/usr/bin/env python3
"""`epa records` against a running appliance (its HTTP API, the [web] token configured): the table
listed (text and --json), one record set in one request and read back through GET /api/records, a
refused value (a target beyond the setpoint range) passed through with the appliance's own words
and nothing of the request applied, the token from EPA_TOKEN, a missing and a wrong token, and an
unreachable URL named.

    records_cli_test.py <epa binary> <source dir>
"""
import json
import os
import subprocess
import sys
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, Appliance, free_port  # noqa: E402

TOKEN = "agqppIImfJRYkrwE1pvb3Ccz"
failures = []


def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def main():
    epa, src = sys.argv[1], sys.argv[2]
    app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), web_static_dir=os.path.join(src, "web"),
                    web_extra=f'token = "{TOKEN}"\n', extra_config="[limits]\nsetpoint_max_mm = 400\n")
    url = f"http://{HOST}:{app.web_port}"
    env = {k: v for k, v in os.environ.items() if k != "EPA_TOKEN"}

    def records(*args, token_env=None):
        e = dict(env, EPA_TOKEN=token_env) if token_env else env
        return subprocess.run([epa, "records", "--url", url, *args], capture_output=True, text=True, timeout=30, env=e)

    def table():
        with urllib.request.urlopen(url + "/api/records", timeout=5) as r:
            return json.load(r)

    try:
        # The table as text and as JSON.
        r = records()
        lines = r.stdout.splitlines()
        check(r.returncode == 0 and lines[0].split() == ["record", "target", "mm", "speed", "limit", "mm/s", "window", "mm", "law", "approach"]
              and len(lines) == 34 and lines[1].split() == ["1", "0.000", "no", "limit", "default", "running", "near"]
              and lines[-1].startswith("record_select: 0"),
              f"`epa records` lists 32 records under a header, then record_select (exit {r.returncode}): {r.stdout[:300]!r} {r.stderr!r}")
        r = records("--json")
        j = json.loads(r.stdout) if r.returncode == 0 else {}
        check(len(j.get("records", [])) == 32 and j.get("record_select") == 0 and j == table(),
              "`epa records --json` is GET /api/records: 32 records, record_select 0")

        # One record set in one request, read back through the API.
        r = records("set", "3", "--target-mm", "123.5", "--speed-mm-s", "40", "--window-mm", "0.8", "--controller", "pp-traj",
                    "--approach", "from-below", "--token", TOKEN)
        rec3 = table()["records"][2]
        check(r.returncode == 0 and rec3 == {"record": 3, "target_mm": 123.5, "speed_mm_s": 40.0, "window_mm": 0.8, "controller": "pp-traj",
                                             "approach": "from-below"},
              f"`epa records set 3 ...` (exit {r.returncode}, {r.stderr.strip()!r}): /api/records has {rec3}")
        check(any(l.split() == ["3", "123.500", "40.000", "0.800", "pp-traj", "from-below"] for l in r.stdout.splitlines()),
              f"`epa records set` shows the record as the appliance holds it: {r.stdout!r}")
        with urllib.request.urlopen(url + "/api/audit", timeout=5) as a:
            audited = {e["point"] for e in json.load(a)["entries"] if e["source"].startswith("web ")}
        check({"record3_target_mm", "record3_speed_mm_s", "record3_window_mm", "record3_controller", "record3_approach"} <= audited,
              f"the five writes are in the audit trail from the web: {sorted(audited)}")

        # A refused value: the appliance's words, and nothing of the request applied.
        r = records("set", "3", "--target-mm", "900", "--speed-mm-s", "10", "--token", TOKEN)
        check(r.returncode == 1 and "HTTP 400" in r.stderr and "record3_target_mm" in r.stderr and "[0, 400]" in r.stderr,
              f"a target beyond the setpoint range [0, 400] is refused with the appliance's reason (exit {r.returncode}): {r.stderr.strip()!r}")
        rec3 = table()["records"][2]
        check(rec3["target_mm"] == 123.5 and rec3["speed_mm_s"] == 40.0,
              f"after the refusal record 3 is unchanged, its speed too (one group, all or nothing): {rec3}")
        r = records("set", "3", "--controller", "pp-fast", "--token", TOKEN)
        check(r.returncode == 1 and "unknown controller 'pp-fast'" in r.stderr, f"an unknown law is named: {r.stderr.strip()!r}")

        # The token: missing, from EPA_TOKEN, wrong.
        r = records("set", "5", "--target-mm", "10")
        check(r.returncode == 1 and "no token" in r.stderr and "EPA_TOKEN" in r.stderr,
              f"without --token or EPA_TOKEN: refused before asking, naming both (exit {r.returncode}): {r.stderr.strip()!r}")
        r = records("set", "5", "--target-mm", "10", token_env=TOKEN)
        check(r.returncode == 0 and table()["records"][4]["target_mm"] == 10.0,
              f"the token from EPA_TOKEN: record 5 set (exit {r.returncode}, {r.stderr.strip()!r})")
        r = records("set", "5", "--target-mm", "20", "--token", "Wq3kZ8vN1xR5tY7pL2mB9cJd")  # strong, but not the one
        check(r.returncode == 1 and "HTTP 401" in r.stderr and "wrong token" in r.stderr and table()["records"][4]["target_mm"] == 10.0,
              f"a wrong token: the appliance's 401 passed through, nothing changed: {r.stderr.strip()!r}")
        r = records("set", "5", "--token", TOKEN)
        check(r.returncode == 1 and "nothing to set" in r.stderr, f"no field given: {r.stderr.strip()!r}")

        # An unreachable appliance is named.
        dead = f"http://{HOST}:{free_port()}"
        r = subprocess.run([epa, "records", "--url", dead], capture_output=True, text=True, timeout=30, env=env)
        check(r.returncode == 1 and f"no answer from {dead}" in r.stderr, f"an unreachable URL is named: {r.stderr.strip()!r}")
    finally:
        status = app.stop()
        if failures:
            print(app.log_text())
        app.remove()
    check(status == 0, f"epa serve stopped cleanly (exit {status})")
    print(f"{len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
