#!/usr/bin/env python3
"""`epa certs` as a user runs it (init, client, revoke), judged from outside by the openssl command
line, which shares no code with ours: the device certificate verifies for sslserver with the names
given, a client certificate for sslclient only, the role extension (OID 1.3.6.1.4.1.50316.802.1) is
one DER UTF8String, keys are mode 0600, existing files and an unsafe name are refused, and after
`epa certs revoke` the revoked client fails `openssl verify -crl_check` while another passes. Last,
a TLS handshake on loopback (Python's ssl on both ends, the files as written): the server with the
CRL accepts the other client and refuses the revoked one.

    certs_cli_test.py <epa binary>

Exits 77 (skipped) when the openssl program is missing.
"""
import os
import re
import shutil
import socket
import ssl
import stat
import subprocess
import sys
import tempfile
import threading

ROLE_OID = "1.3.6.1.4.1.50316.802.1"
failures = []


def check(ok, what):
    print(("PASS: " if ok else "FAIL: ") + what)
    if not ok:
        failures.append(what)


def run(*args, cwd=None):
    return subprocess.run(list(args), capture_output=True, text=True, timeout=60, cwd=cwd)


def handshake(pki, client):
    """A TLS server with the device certificate, the CA and the CRL (leaf checked), and a client
    with `client`.pem that checks the server's name; what each end saw."""
    server_ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    server_ctx.load_cert_chain(os.path.join(pki, "device.pem"), os.path.join(pki, "device.key"))
    server_ctx.load_verify_locations(cafile=os.path.join(pki, "ca.pem"))
    server_ctx.load_verify_locations(cafile=os.path.join(pki, "crl.pem"))
    server_ctx.verify_mode = ssl.CERT_REQUIRED
    server_ctx.verify_flags |= ssl.VERIFY_CRL_CHECK_LEAF
    client_ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    client_ctx.load_verify_locations(cafile=os.path.join(pki, "ca.pem"))
    client_ctx.load_cert_chain(os.path.join(pki, client + ".pem"), os.path.join(pki, client + ".key"))

    seen = {}
    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(20)
    port = listener.getsockname()[1]

    def serve():
        try:
            conn, _ = listener.accept()
            conn.settimeout(20)
            with server_ctx.wrap_socket(conn, server_side=True) as tls:
                tls.sendall(b"ok")
                seen["server"] = "accepted " + tls.getpeercert()["subject"][0][0][1]
        except (ssl.SSLError, OSError) as e:
            seen["server"] = str(e)

    thread = threading.Thread(target=serve)
    thread.start()
    try:
        with socket.create_connection(("127.0.0.1", port), timeout=20) as raw:
            with client_ctx.wrap_socket(raw, server_hostname="localhost") as tls:
                seen["client"] = "read " + tls.recv(2).decode()
    except (ssl.SSLError, OSError) as e:
        seen["client"] = str(e)
    thread.join(30)
    listener.close()
    return seen


def main():
    epa = os.path.abspath(sys.argv[1])
    if shutil.which("openssl") is None:
        print("SKIP: no openssl program")
        return 77
    with tempfile.TemporaryDirectory(prefix="epa-certs-") as tmp:
        pki = os.path.join(tmp, "pki")

        def at(name):
            return os.path.join(pki, name)

        def certs(*args):
            return run(epa, "certs", *args, cwd=tmp)

        def openssl(*args):
            return run("openssl", *args, cwd=pki)

        # init: five files, one line each; the device certificate for servers, with the names given.
        r = certs("init", "pki", "--cn", "plc-7", "--dns", "plc-7.plant.example", "--dns", "localhost", "--ip", "127.0.0.1,::1")
        lines = r.stdout.splitlines()
        check(r.returncode == 0 and [line.split(":")[0] for line in lines] == [
            "wrote pki/ca.key", "wrote pki/ca.pem", "wrote pki/device.key", "wrote pki/device.pem", "wrote pki/crl.pem"],
            f"`epa certs init` writes ca.key, ca.pem, device.key, device.pem, crl.pem, one line each (exit {r.returncode}): "
            f"{r.stdout!r} {r.stderr!r}")
        for key in ("ca.key", "device.key"):
            mode = stat.S_IMODE(os.stat(at(key)).st_mode) if os.path.exists(at(key)) else None
            check(mode == 0o600, f"{key} is mode 0600 (it is {oct(mode) if mode is not None else 'missing'})")
        v = openssl("verify", "-CAfile", "ca.pem", "-purpose", "sslserver", "device.pem")
        check(v.returncode == 0 and "device.pem: OK" in v.stdout, f"openssl verify -purpose sslserver device.pem: {v.stdout!r} {v.stderr!r}")
        v = openssl("x509", "-in", "device.pem", "-noout", "-subject", "-ext", "subjectAltName,extendedKeyUsage")
        check(v.returncode == 0 and "CN = plc-7" in v.stdout and "DNS:plc-7.plant.example" in v.stdout and "DNS:localhost" in v.stdout
              and "IP Address:127.0.0.1" in v.stdout and "IP Address:0:0:0:0:0:0:0:1" in v.stdout
              and "TLS Web Server Authentication" in v.stdout,
              f"openssl x509 shows CN plc-7, the DNS names and addresses given, serverAuth: {v.stdout!r} {v.stderr!r}")
        v = openssl("x509", "-in", "ca.pem", "-noout", "-ext", "basicConstraints,keyUsage")
        check(v.returncode == 0 and re.search(r"Basic Constraints: critical\s+CA:TRUE", v.stdout) is not None
              and "Certificate Sign, CRL Sign" in v.stdout, f"the CA is CA:TRUE (critical), keyCertSign and cRLSign: {v.stdout!r}")

        # client: one certificate a client, for clients only, carrying its role.
        r = certs("client", "pki", "hmi-1", "--role", "operator")
        check(r.returncode == 0 and "wrote pki/hmi-1.pem" in r.stdout and "wrote pki/hmi-1.key" in r.stdout
              and "subject /CN=hmi-1, role operator" in r.stdout,
              f"`epa certs client pki hmi-1 --role operator` names its files, subject and role: {r.stdout!r} {r.stderr!r}")
        r = certs("client", "pki", "hmi-2", "--role", "viewer")
        check(r.returncode == 0, f"a second client, hmi-2 (viewer): {r.stderr!r}")
        mode = stat.S_IMODE(os.stat(at("hmi-1.key")).st_mode) if os.path.exists(at("hmi-1.key")) else None
        check(mode == 0o600, f"hmi-1.key is mode 0600 ({oct(mode) if mode is not None else 'missing'})")
        v = openssl("verify", "-CAfile", "ca.pem", "-purpose", "sslclient", "hmi-1.pem")
        check(v.returncode == 0 and "hmi-1.pem: OK" in v.stdout, f"openssl verify -purpose sslclient hmi-1.pem: {v.stdout!r} {v.stderr!r}")
        v = openssl("verify", "-CAfile", "ca.pem", "-purpose", "sslserver", "hmi-1.pem")
        check(v.returncode != 0, f"a client certificate does not verify for sslserver: {v.stdout!r} {v.stderr!r}")
        v = openssl("x509", "-in", "hmi-1.pem", "-noout", "-text")
        check(v.returncode == 0 and re.search(re.escape(ROLE_OID) + r":\s*\n\s*\S*operator", v.stdout) is not None
              and "TLS Web Client Authentication" in v.stdout,
              f"openssl x509 -text shows the extension {ROLE_OID} with 'operator', and clientAuth")
        # The extension's value, as DER: UTF8String (0x0c), 8 bytes, "operator".
        v = openssl("asn1parse", "-in", "hmi-1.pem")
        check(re.search(r":" + re.escape(ROLE_OID) + r"\s*\n.*OCTET STRING\s+\[HEX DUMP\]:0C086F70657261746F72\s*$", v.stdout, re.M) is not None,
              f"openssl asn1parse: the role extension's value is the DER of UTF8String 'operator': {v.stdout[-600:]!r}")

        # Refusals: existing files, an unsafe name, a missing role.
        before = open(at("ca.pem")).read()
        r = certs("init", "pki")
        check(r.returncode == 1 and r.stderr.startswith("epa certs: ") and "pki/ca.pem exists" in r.stderr and "--force" in r.stderr
              and open(at("ca.pem")).read() == before,
              f"a second init is refused, naming pki/ca.pem and --force, and ca.pem is kept (exit {r.returncode}): {r.stderr!r}")
        r = certs("client", "pki", "../evil", "--role", "operator")
        check(r.returncode == 1 and "'../evil' is not a safe file name" in r.stderr and not os.path.exists(os.path.join(tmp, "evil.pem")),
              f"a client named ../evil is refused, nothing written (exit {r.returncode}): {r.stderr!r}")
        r = certs("client", "pki", "hmi-3")
        check(r.returncode == 106 and "--role is required" in r.stderr, f"a client without --role: exit 106 (exit {r.returncode}): {r.stderr!r}")

        # revoke: the empty list of init passes everyone; after the revocation hmi-1 fails, hmi-2 passes.
        v = openssl("verify", "-crl_check", "-CRLfile", "crl.pem", "-CAfile", "ca.pem", "hmi-1.pem")
        check(v.returncode == 0, f"before the revocation hmi-1 passes the CRL check of init's empty list: {v.stdout!r} {v.stderr!r}")
        serial = openssl("x509", "-in", "hmi-1.pem", "-noout", "-serial").stdout.strip().removeprefix("serial=")
        r = certs("revoke", "pki", "pki/hmi-1.pem")
        check(r.returncode == 0 and f"revoked: /CN=hmi-1, serial {serial}" in r.stdout and "wrote pki/crl.pem" in r.stdout,
              f"`epa certs revoke pki pki/hmi-1.pem` (serial {serial}): {r.stdout!r} {r.stderr!r}")
        v = openssl("crl", "-in", "crl.pem", "-noout", "-text", "-CAfile", "ca.pem")
        check(v.returncode == 0 and f"Serial Number: {serial}" in v.stdout and "verify OK" in (v.stdout + v.stderr),
              f"openssl crl: signed by the CA, lists hmi-1's serial: {v.stdout!r} {v.stderr!r}")
        v = openssl("verify", "-crl_check", "-CRLfile", "crl.pem", "-CAfile", "ca.pem", "hmi-1.pem")
        check(v.returncode != 0 and "certificate revoked" in (v.stdout + v.stderr),
              f"openssl verify -crl_check refuses the revoked hmi-1: {v.stdout!r} {v.stderr!r}")
        v = openssl("verify", "-crl_check", "-CRLfile", "crl.pem", "-CAfile", "ca.pem", "-purpose", "sslclient", "hmi-2.pem")
        check(v.returncode == 0 and "hmi-2.pem: OK" in v.stdout, f"openssl verify -crl_check passes hmi-2: {v.stdout!r} {v.stderr!r}")

        # The files in a real handshake: the server with the CRL takes hmi-2 and refuses hmi-1.
        seen = handshake(pki, "hmi-2")
        check(seen.get("server") == "accepted hmi-2" and seen.get("client") == "read ok", f"a TLS handshake with hmi-2 succeeds: {seen}")
        seen = handshake(pki, "hmi-1")
        check("certificate revoked" in seen.get("server", "") and seen.get("client") != "read ok",
              f"a TLS handshake with the revoked hmi-1 is refused by the server: {seen}")

    print(f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
