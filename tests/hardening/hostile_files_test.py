#!/usr/bin/env python3
"""Hostile files, as an attacker who can hand the operator a file would try them: every reader of
the `epa` command line gets /dev/zero, a FIFO, a 1 GB sparse file, a polynomial of 100,000
coefficients and a document nested 200,000 levels deep (each where the format allows it). Each must
end within 2 s, non-zero, with a message naming the file. Then the tuning import:

  unstable set  F = [1, -3, 5] on the paper's model: refused with exit 3, naming the set and the
                branches, as `epa design` refuses it; nothing is stored
  names         a set name with ESC, one with a newline (in the file and with --name) and one of
                1 MB: refused naming the rule; `epa tuning list` shows none of them

    hostile_files_test.py <epa binary> <source dir>

Runs in a scratch folder (removed at the end); no network beyond the loopback port 0 of one short
`epa serve` that seeds the store. Exit 0 when every row holds, 1 otherwise (each failure says what
was expected and what came back).
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

LIMIT_S = 2.0
failures = []


def run(epa, args, cwd):
    start = time.monotonic()
    try:
        p = subprocess.run([epa] + args, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=20,
                           stdin=subprocess.DEVNULL)
        return p.returncode, p.stdout.decode("utf-8", "replace"), time.monotonic() - start
    except subprocess.TimeoutExpired:
        return None, "(killed after 20 s)", time.monotonic() - start


def check(label, ok, detail):
    print(("ok    " if ok else "FAIL  ") + label + ("" if ok else ": " + detail))
    if not ok:
        failures.append(label)


def expect_refused(epa, label, args, path, cwd, exit_code=None):
    code, out, took = run(epa, args, cwd)
    named = path in out
    ok = code not in (0, None) and took < LIMIT_S and named and (exit_code is None or code == exit_code)
    check(f"{label} ({took:.2f} s)", ok, f"exit {code}, {took:.2f} s, file named: {named}, output: {out[-400:]!r}")
    return out


def write(path, text):
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def hostile_inputs(d):
    """name -> path for each hostile input; the format-specific ones by format."""
    fifo = os.path.join(d, "fifo")
    os.mkfifo(fifo)
    big = os.path.join(d, "big")
    with open(big, "wb") as f:
        f.truncate(1 << 30)  # sparse: no disk used
    many = ", ".join(["0.0"] * 100000)
    deep_toml = "schema = \"epa-model/1\"\nx = " + "[" * 200000 + "]" * 200000 + "\n"
    deep_json = "[" * 200000 + "]" * 200000
    return {
        "zero": "/dev/zero",
        "fifo": fifo,
        "big": big,
        "model_coefficients": write(os.path.join(d, "many.toml"),
                                    "schema = \"epa-model/1\"\nTs = 0.005\n[arx]\nA = [1.0, " + many + "]\nB = [0.0, 1.0]\n"
                                    "[dead_zone]\nm_r = 1.0\nm_l = 1.0\nb_r = 1.0\nb_l = -1.0\n"),
        "design_coefficients": write(os.path.join(d, "many.json"),
                                     "{\"schema\": \"epa-design/1\", \"F\": [1.0, " + many + "], \"G\": [1.0], \"H\": [1.0]}"),
        "deep_toml": write(os.path.join(d, "deep.toml"), deep_toml),
        "deep_json": write(os.path.join(d, "deep.json"), deep_json),
    }


def readers(h, d, src):
    """(label, argv, hostile path) for every reader and the hostile inputs its format admits."""
    common = ["zero", "fifo", "big"]
    rows = []
    for k in common + ["deep_toml"]:
        rows.append((f"serve --config {k}", ["serve", "--config", h[k], "--duration", "0.3"], h[k]))
    for k in common:
        rows.append((f"registers {k}", ["registers", h[k]], h[k]))
        rows.append((f"identify {k}", ["identify", h[k]], h[k]))
        rows.append((f"diagnose {k}", ["diagnose", h[k], "--holdout", h[k]], h[k]))
        rows.append((f"commission --token-file {k}", ["commission", "--token-file", h[k], "--url", "http://127.0.0.1:9"], h[k]))
        rows.append((f"simulate physics config {k}", ["simulate", "--plant", "physics", "--physics-config", h[k]], h[k]))
    for k in common + ["model_coefficients", "deep_toml"]:
        rows.append((f"design --model {k}", ["design", "--model", h[k]], h[k]))
        rows.append((f"simulate --model {k}", ["simulate", "--model", h[k]], h[k]))
        rows.append((f"tuning import {k}", ["tuning", "--db", os.path.join(d, "epa.db"), "import", h[k]], h[k]))
    for k in common + ["design_coefficients", "deep_json"]:
        rows.append((f"design --design {k}", ["design", "--design", h[k]], h[k]))
    for k in common + ["deep_json"]:
        rows.append((f"commission --spec {k}", ["commission", "--spec", h[k], "--token", "x", "--url", "http://127.0.0.1:9"], h[k]))
    return rows


def seed_store(epa, d, src):
    write(os.path.join(d, "epa.toml"),
          f"[log]\nstatus_interval_s = 0\n[modbus]\nport = 0\nregister_map = \"{src}/registers/epa.csv\"\n"
          f"[web]\nenabled = false\n[store]\npath = \"{d}/epa.db\"\n[recorder]\ndirectory = \"{d}/runs\"\n")
    code, out, _ = run(epa, ["serve", "--config", os.path.join(d, "epa.toml"), "--duration", "0.3"], d)
    if code != 0:
        sys.exit(f"cannot seed the store (exit {code}): {out}")
    code, out, _ = run(epa, ["tuning", "--db", os.path.join(d, "epa.db"), "export", "paper", "--out", os.path.join(d, "paper.toml")], d)
    if code != 0:
        sys.exit(f"cannot export the paper set (exit {code}): {out}")
    with open(os.path.join(d, "paper.toml"), encoding="utf-8") as f:
        return f.read()


def tuning_import_rows(epa, d, paper):
    db = ["tuning", "--db", os.path.join(d, "epa.db")]
    unstable = re.sub(r"(?m)^F = \[.*\]$", "F = [1.0, -3.0, 5.0]", paper).replace("name = 'paper'", 'name = "unstable"', 1)
    assert unstable != paper
    out = expect_refused(epa, "tuning import of an unstable set: exit 3", db + ["import", write(os.path.join(d, "u.toml"), unstable)],
                         "u.toml", d, exit_code=3)
    check("the refusal names the set and a branch", "'unstable'" in out and "nominal" in out and "UNSTABLE" in out, out)
    for label, name in [("ESC", "evil\\u001b[2J"), ("newline", "evil\\nINFO forged line"), ("1 MB", "x" * (1 << 20))]:
        text = paper.replace("name = 'paper'", f'name = "{name}"', 1)
        assert text != paper
        path = write(os.path.join(d, "n.toml"), text)
        code, out, took = run(epa, db + ["import", path], d)
        check(f"a set name with {label} in the file is refused naming the rule ({took:.2f} s)",
              code not in (0, None) and took < LIMIT_S and "printable characters on one line" in out, f"exit {code}: {out[-300:]!r}")
    for label, name in [("ESC", "evil\x1b[2J"), ("newline", "evil\nINFO forged line")]:
        code, out, _ = run(epa, db + ["import", os.path.join(d, "paper.toml"), "--name", name], d)
        check(f"--name with {label} is refused naming the rule", code not in (0, None) and "printable characters" in out,
              f"exit {code}: {out[-300:]!r}")
    code, out, _ = run(epa, db + ["import", os.path.join(d, "paper.toml"), "--name", "copy of paper"], d)
    check("a stable set with a plain name still imports", code == 0, f"exit {code}: {out!r}")
    code, out, _ = run(epa, db + ["list"], d)
    check("tuning list holds none of the refused sets", code == 0 and "unstable" not in out and "evil" not in out
          and "\x1b" not in out and "copy of paper" in out, out)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    d = tempfile.mkdtemp(prefix="epa-hostile-files-")
    try:
        paper = seed_store(epa, d, src)
        h = hostile_inputs(d)
        for label, args, path in readers(h, d, src):
            expect_refused(epa, label, args, path, d)
        tuning_import_rows(epa, d, paper)
    finally:
        shutil.rmtree(d, ignore_errors=True)
    print(f"{len(failures)} failed" if failures else "all rows hold")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
