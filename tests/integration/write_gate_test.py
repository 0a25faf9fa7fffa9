#!/usr/bin/env python3
"""The one write gate, end to end, as an integrator meets it: `epa serve` with [limits]
setpoint_max_mm = 300 while the shipped register map keeps its 0..500 range, driven by pymodbus
and plain HTTP (clients this project did not write).

    write_gate_test.py <epa binary> <source dir>

Checks: FC16 setpoint 400.0 gets exception 03, no audit entry, the setpoint register keeps its
value; POST /api/setpoint 400 gets HTTP 400 naming [limits] setpoint_max_mm; every writable point
of GET /api/points written just beyond its range over HTTP gets 400 and over Modbus (where the
map binds it and the register type can carry the value) exception 03; 300 is taken by both and
audited once each; after a stop the database's audit log holds exactly the two accepted changes
and the unlock that opened the tuning points for the walk (unlock 0 -> 1): no refused write.
And start-up: a register map whose default lies outside the configuration's limits is refused,
naming the map's file and line.
"""
import json
import math
import os
import sqlite3
import subprocess
import sys
import urllib.error
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import UNIT, Appliance, Checks, f32_value, f32_words, pymodbus, unlock  # noqa: E402

TOKEN = "mteO0wA4Az6ZNXI75tnO0ToT"
ILLEGAL_VALUE = 0x03


def http(app, method, path, body=None):
    req = urllib.request.Request(f"http://127.0.0.1:{app.web_port}{path}", method=method,
                                 data=None if body is None else json.dumps(body).encode(),
                                 headers={"Authorization": f"Bearer {TOKEN}", "Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read())
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read())


def beyond(bound, direction):
    return bound + direction * max(1.0, abs(bound) * 1e-3)


def main():
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir>")
    epa, src = sys.argv[1], sys.argv[2]
    check = Checks()
    failures = check.failures

    reg_map = os.path.join(src, "registers", "epa.csv")
    app = Appliance(epa, reg_map, "[limits]\nsetpoint_max_mm = 300.0\n", web_static_dir=os.path.join(src, "web"),
                    web_extra=f'token = "{TOKEN}"\n')
    try:
        c = app.client
        rr = c.write_registers(0, f32_words(400.0, "ABCD"), slave=UNIT)
        check(rr.isError() and getattr(rr, "exception_code", None) == ILLEGAL_VALUE, f"FC16 setpoint 400 -> exception 03 ({rr})")
        setpoint = f32_value(c.read_holding_registers(0, 2, slave=UNIT).registers, "ABCD")
        check(setpoint == 0.0, f"the setpoint register keeps 0 ({setpoint})")

        status, body = http(app, "POST", "/api/setpoint", {"setpoint_mm": 400})
        check(status == 400 and "setpoint_max_mm" in body.get("error", ""), f"POST /api/setpoint 400 -> 400 naming the limit ({status} {body})")

        # Every writable point, just beyond its range, through both interfaces.
        unlock(c)  # unlocked: only the range can refuse tuning writes
        _, catalog = http(app, "GET", "/api/points")
        holding = {}  # point -> (address, type) of the shipped map's float32 / uint16 holding registers
        for line in open(reg_map):
            f = line.rstrip("\n").split(",")
            if len(f) > 8 and f[1] == "holding" and f[7] == "rw":
                holding[f[0]] = (int(f[2]), f[3])
        walked = modbus_walked = 0
        for p in catalog["points"]:
            if "max" not in p:
                continue
            for v in (beyond(p["max"], +1), beyond(p["min"], -1)):
                status, body = http(app, "POST", "/api/points", {p["name"]: v})
                check(status == 400 and p["name"] in body.get("error", ""), f"HTTP {p['name']} = {v:g} -> 400 ({status} {body})")
                walked += 1
                if p["name"] in holding:
                    address, kind = holding[p["name"]]
                    if kind == "float32" and math.isfinite(v) and abs(v) < 3e38:
                        rr = c.write_registers(address, f32_words(v, "ABCD"), slave=UNIT)
                    elif kind == "uint16" and 0 <= v <= 65535 and v == int(v):
                        rr = c.write_register(address, int(v), slave=UNIT)
                    else:
                        continue
                    check(rr.isError() and getattr(rr, "exception_code", None) == ILLEGAL_VALUE,
                          f"Modbus {p['name']} = {v:g} -> exception 03 ({rr})")
                    modbus_walked += 1
        check(walked >= 24 and modbus_walked >= 12, f"walked {walked} out-of-range writes over HTTP, {modbus_walked} over Modbus")

        rr = c.write_registers(0, f32_words(300.0, "ABCD"), slave=UNIT)
        check(not rr.isError(), "FC16 setpoint 300 is taken")
        status, body = http(app, "POST", "/api/setpoint", {"setpoint_mm": 250})
        check(status == 200, f"POST /api/setpoint 250 is taken ({status} {body})")
        _, audit = http(app, "GET", "/api/audit")
        points = [(e["point"], e["new_value"]) for e in audit["entries"]]
        check(sorted(points) == [("setpoint_mm", 250.0), ("setpoint_mm", 300.0), ("unlock", 1.0)],
              f"the audit trail holds the unlock and the two accepted writes only ({points})")
    finally:
        app.stop()
    db = sqlite3.connect(app.db)
    rows = db.execute("SELECT point, new_value FROM audit_log ORDER BY id").fetchall()
    db.close()
    check(rows == [("unlock", 1.0), ("setpoint_mm", 300.0), ("setpoint_mm", 250.0)], f"the database's audit log: {rows}")
    app.remove()

    # A map whose default the configuration's limits exclude: refused at start-up, naming file and line.
    bad = Appliance(epa, reg_map, "[limits]\nsetpoint_max_mm = 300.0\n", start=False)
    try:
        bad_map = os.path.join(bad.dir, "site.csv")
        with open(reg_map) as f, open(bad_map, "w") as out:
            for line in f:
                out.write(line.replace("setpoint_mm,holding,0,float32,ABCD,,,rw,0,500,0,", "setpoint_mm,holding,0,float32,ABCD,,,rw,0,500,400,"))
        text = open(bad.config).read().replace(reg_map, bad_map)
        open(bad.config, "w").write(text)
        r = subprocess.run([epa, "serve", "--config", bad.config, "--duration", "1"], capture_output=True, text=True, timeout=30)
        check(r.returncode != 0 and "site.csv:4" in r.stderr and "setpoint_max_mm" in r.stderr,
              f"a map default outside the limits is refused at start-up ({r.returncode}: {r.stderr.strip()})")
    finally:
        bad.remove()

    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
