#!/usr/bin/env python3
"""HTTPS on the status page's port, judged from outside by curl, which shares no code with ours:
`epa serve` with [web] tls = true and the files of `epa certs` ([modbus_tls] ca, cert, key, crl,
Modbus/TCP Security itself off). With --cacert the API and the page answer (by address and by the
name localhost); without it curl refuses the certificate; plain HTTP and TLS 1.1 get no answer. A
client certificate logs in by its role: an operator's setpoint is taken without a token and audited
by its subject, a viewer's refused 403 naming the role, a revoked one refused in the handshake and
logged naming it; the refusals of one address are logged once. Without a certificate the token rule holds (401 without, 200 with).

    https_curl_test.py <epa binary> <source dir>

Exits 77 (skipped) when curl is missing.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import HOST, Appliance  # noqa: E402

TOKEN = "Hq7vL2pXw9RcT4mZk8NbF3sY"
failures = []


def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def run(*args):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=60)


def main():
    if len(sys.argv) != 3:
        print(f"usage: {sys.argv[0]} <epa binary> <source dir>", file=sys.stderr)
        return 2
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if not shutil.which("curl"):
        print("SKIP: curl is not installed (scripts/install-deps.sh installs it)")
        return 77
    pki = tempfile.mkdtemp(prefix="epa-https-pki.")
    app = None
    try:
        # The plant's CA as a commissioning engineer makes it; one client revoked before the start.
        for cmd in (["init", pki], ["client", pki, "hmi-op", "--role", "operator"], ["client", pki, "panel", "--role", "viewer"],
                    ["client", pki, "old-laptop", "--role", "engineer"], ["revoke", pki, os.path.join(pki, "old-laptop.pem")]):
            r = run(epa, "certs", *cmd)
            if r.returncode != 0:
                check(False, f"epa certs {' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()}")
                return 1
        files = "".join(f'{key} = "{os.path.join(pki, name)}"\n'
                        for key, name in (("ca", "ca.pem"), ("cert", "device.pem"), ("key", "device.key"), ("crl", "crl.pem")))
        app = Appliance(epa, os.path.join(src, "registers", "epa.csv"), web_static_dir=os.path.join(src, "web"),
                        modbus_extra="[modbus_tls]\n" + files, web_extra=f'tls = true\ntoken = "{TOKEN}"\n')
        base = f"https://{HOST}:{app.web_port}"
        ca = ["--cacert", os.path.join(pki, "ca.pem")]

        def cert(name):
            return ["--cert", os.path.join(pki, name + ".pem"), "--key", os.path.join(pki, name + ".key")]

        def curl(path, *extra, url=base):
            """(curl's exit status, HTTP status, body)"""
            r = run("curl", "-s", "--max-time", "10", "-w", "\n%{http_code}", *extra, url + path)
            body, _, code = r.stdout.rpartition("\n")
            return r.returncode, code, body

        def post(path, body, *extra):
            return curl(path, *ca, "-X", "POST", "-H", "Content-Type: application/json", "-d", body, *extra)

        rc, code, body = curl("/api/status", *ca)
        status = json.loads(body) if rc == 0 and code == "200" else {}
        check(status.get("mode") == "stop", f"curl --cacert ca.pem {base}/api/status: 200 with the status (exit {rc}, HTTP {code})")
        rc, code, body = curl("/", *ca, url=f"https://localhost:{app.web_port}")
        check(rc == 0 and code == "200" and "app.js" in body, f"the page by the name localhost, verified against the CA (exit {rc}, HTTP {code})")
        rc, _, _ = curl("/api/status")
        check(rc == 60, f"without --cacert curl refuses the appliance's certificate (exit {rc}, 60 expected)")
        rc, code, _ = curl("/api/status", url=f"http://{HOST}:{app.web_port}")
        check(rc != 0 and code == "000", f"plain HTTP on the HTTPS port gets no answer (exit {rc}, HTTP {code})")
        rc, code, _ = curl("/api/status", *ca, "--tlsv1.1", "--tls-max", "1.1")
        check(rc != 0 and code == "000", f"TLS 1.1 gets no session (exit {rc}, HTTP {code})")

        rc, code, body = post("/api/setpoint", '{"setpoint_mm": 120}', *cert("hmi-op"))
        check(rc == 0 and code == "200", f"an operator certificate's setpoint, no token: HTTP {code} {body}")
        rc, code, body = curl("/api/audit", *ca)
        sources = [e["source"] for e in json.loads(body)["entries"]] if code == "200" else []
        check("web 127.0.0.1 /CN=hmi-op (operator)" in sources, f"the audit names the certificate's subject and role: {sources}")
        rc, code, body = post("/api/setpoint", '{"setpoint_mm": 130}', *cert("panel"), "-H", f"Authorization: Bearer {TOKEN}")
        check(code == "403" and 'role \\"viewer\\" has read rights only' in body, f"a viewer certificate's setpoint, even with the token: HTTP {code} {body}")
        # From an address of its own: the refusals of 127.0.0.1 above were logged once, the rest held back.
        rc, code, _ = post("/api/setpoint", '{"setpoint_mm": 130}', *cert("old-laptop"), "--interface", "127.0.0.2")
        check(rc != 0 and code == "000", f"a revoked certificate gets no session (exit {rc}, HTTP {code})")
        rc, code, _ = post("/api/setpoint", '{"setpoint_mm": 140}')
        check(code == "401", f"no certificate, no token: HTTP {code}")
        rc, code, body = post("/api/setpoint", '{"setpoint_mm": 140}', "-H", f"Authorization: Bearer {TOKEN}")
        check(code == "200", f"no certificate, the token: HTTP {code} {body}")

        log = app.log_text()
        check(f"web: listening on {HOST}:{app.web_port} (HTTPS only" in log, "the log says the web port speaks HTTPS only")
        refused = [line for line in log.splitlines() if "refused in the TLS handshake" in line]
        check(len([line for line in refused if "web: 127.0.0.1 refused" in line]) == 1,
              f"the refusals from 127.0.0.1 (a client that does not trust the CA, plain HTTP), one line: {refused}")
        check(any("web: 127.0.0.2 refused" in line and "/CN=old-laptop: certificate revoked" in line for line in refused),
              f"the revoked certificate's refusal is logged naming it: {refused}")
    finally:
        status = app.stop() if app else 0
        if failures and app:
            print(app.log_text())
        if app:
            app.remove()
        shutil.rmtree(pki, ignore_errors=True)
    check(status == 0, f"epa serve stopped cleanly (exit {status})")
    print(f"{len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
