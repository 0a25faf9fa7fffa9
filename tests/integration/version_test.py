#!/usr/bin/env python3
"""One version everywhere: CMakeLists.txt's project(VERSION) is what `epa --version` prints, what
the Modbus registers version_major/minor/patch (input 12-14 of registers/epa.csv) and device
identification's MajorMinorRevision (FC43/14, object 0x02) say, what GET /api/status's "version"
and /metrics' epa_build_info name.

    version_test.py <epa binary> <source dir> <project version from CMake>

Starts `epa serve` on free loopback ports (Modbus and web), stops it by its PID.
"""
import json
import os
import re
import subprocess
import sys
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import UNIT, Appliance  # noqa: E402
from pymodbus.mei_message import ReadDeviceInformationRequest  # noqa: E402


def main():
    if len(sys.argv) != 4:
        sys.exit(f"usage: {sys.argv[0]} <epa binary> <source dir> <project version>")
    epa, src, expected = sys.argv[1], sys.argv[2], sys.argv[3]
    failures, passes = [], []

    def check(ok, what):
        print(("PASS: " if ok else "FAIL: ") + what)
        (passes if ok else failures).append(what)

    check(re.fullmatch(r"\d+\.\d+\.\d+", expected) is not None, f"CMake's project version is MAJOR.MINOR.PATCH ({expected})")
    out = subprocess.run([epa, "--version"], capture_output=True, text=True, timeout=10)
    check(out.returncode == 0 and out.stdout.strip() == f"epa {expected}", f"epa --version prints 'epa {expected}' ({out.stdout.strip()!r})")

    app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), web_static_dir=os.path.join(src, "web"))
    try:
        rr = app.client.read_input_registers(12, 3, slave=UNIT)
        registers = "" if rr.isError() else ".".join(str(r) for r in rr.registers)
        check(registers == expected, f"Modbus input 12-14 (version_major/minor/patch) read {registers or rr}")
        rr = app.client.execute(ReadDeviceInformationRequest(read_code=0x04, object_id=0x02, unit=UNIT))
        revision = "" if rr.isError() else rr.information.get(0x02, b"").decode()
        check(revision == expected, f"FC43/14 MajorMinorRevision (object 0x02) is {revision or rr}")
        base = f"http://127.0.0.1:{app.web_port}"
        with urllib.request.urlopen(base + "/api/status", timeout=5) as r:
            status = json.loads(r.read())
        check(status.get("version") == expected, f"GET /api/status \"version\" is {status.get('version')!r}")
        with urllib.request.urlopen(base + "/metrics", timeout=5) as r:
            metrics = r.read().decode()
        check(f'epa_build_info{{version="{expected}"}} 1' in metrics.splitlines(), "/metrics epa_build_info names it")
    finally:
        status = app.stop()
        app.remove()
    check(status == 0, f"epa serve exited with {status} after SIGTERM")
    print(f"{len(passes)} passed, {len(failures)} failed")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
