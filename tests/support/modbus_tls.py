"""Shared by the tests of Modbus/TCP Security: certificates made by `epa certs` (the plant's CA
with clients of given roles, some revoked, and another CA with a client of its own), the
[modbus_tls] section that serves them on 127.0.0.1, and a client's TLS context trusting a CA."""
import os
import ssl
import subprocess


def run(cmd):
    """Runs a command; its standard output, or RuntimeError with its error output."""
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}): {r.stderr}")
    return r.stdout


def make_pki(epa, root, clients, revoked=()):
    """root/pki: the plant's CA with `clients` [(name, role)], those named in `revoked` on its CRL;
    root/other: another CA with an operator "hmi". Returns (pki, other)."""
    pki, other = os.path.join(root, "pki"), os.path.join(root, "other")
    run([epa, "certs", "init", pki])
    for name, role in clients:
        run([epa, "certs", "client", pki, name, "--role", role])
    for name in revoked:
        run([epa, "certs", "revoke", pki, os.path.join(pki, name + ".pem")])
    run([epa, "certs", "init", other])
    run([epa, "certs", "client", other, "hmi", "--role", "operator"])
    return pki, other


def tls_section(pki, port, extra=""):
    """[modbus_tls] on 127.0.0.1:`port` with the files of `pki`, and `extra` keys."""
    return ("[modbus_tls]\nenabled = true\naddress = \"127.0.0.1\"\n"
            f"port = {port}\n{extra}"
            f'ca = "{pki}/ca.pem"\ncert = "{pki}/device.pem"\nkey = "{pki}/device.key"\ncrl = "{pki}/crl.pem"\n')


def client_context(ca_dir, cert_dir=None, name=None):
    """A client's TLS context trusting ca_dir/ca.pem, with cert_dir/name.pem and its key when named."""
    ctx = ssl.create_default_context(ssl.Purpose.SERVER_AUTH, cafile=os.path.join(ca_dir, "ca.pem"))
    if name:
        ctx.load_cert_chain(os.path.join(cert_dir or ca_dir, name + ".pem"), os.path.join(cert_dir or ca_dir, name + ".key"))
    return ctx
