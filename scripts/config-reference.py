#!/usr/bin/env python3
"""Write docs/configuration-reference.md from config/epa.toml's comments.

Usage:
  scripts/config-reference.py          write the file
  scripts/config-reference.py --check  exit 1 and show the difference when the file is stale

The shipped configuration is commented key by key; this script turns those comments into one
table per section. Each numeric key's accepted range is read from where the appliance checks it,
src/config/appliance_config.cpp (TableReader calls such as
`lim.number("soft_min_mm", ..., closed(-10000, 10000, "mm"))`). Python 3 standard library only.
"""
import difflib
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
CONFIG = ROOT / "config" / "epa.toml"
LOADER = ROOT / "src" / "config" / "appliance_config.cpp"
OUTPUT = ROOT / "docs" / "configuration-reference.md"

# Comments in config/epa.toml that point at README sections which now live in docs/.
REWRITES = []  # (old, new) wording changes for the generated page, none at present

# Named constants the loader uses as bounds.
CONSTANTS = {
    "kDay_s": 86400,
    "core::kAuditMinRows": 1000,
    "hal::kMaxRegisterAddress": 65535,
    "std::int64_t{1'000'000'000}": 1000000000,
}


def strip_comment(line):
    """Split a TOML line into (code, comment) at the first # outside a string."""
    quote = None
    for i, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return line[:i].rstrip(), line[i + 1:].strip()
    return line.rstrip(), ""


def parse_config(text):
    """Return (preamble, sections): sections is a list of dicts with name, notes and keys."""
    preamble = []
    sections = []
    current = None
    last = None  # the key or section the next comment-only line continues
    for raw in text.splitlines():
        line = raw.rstrip()
        if not line.strip():
            last = None
            continue
        code, comment = strip_comment(line)
        if not code.strip():
            # A comment-only line: indented, it continues the key or section above it; at the
            # start of the line, it is a note on the section.
            if current is None:
                preamble.append(comment)
            elif last is not None and not line.startswith("#"):
                last["comment"].append(comment)
            else:
                current["notes"].append(comment)
            continue
        header = re.fullmatch(r"\s*\[([A-Za-z0-9_.]+)\]\s*", code)
        if header:
            current = {"name": header.group(1), "notes": [], "comment": [comment] if comment else [], "keys": []}
            sections.append(current)
            last = current
            continue
        pair = re.fullmatch(r"\s*([A-Za-z0-9_]+)\s*=\s*(.*)", code)
        if not pair or current is None:
            raise SystemExit(f"{CONFIG}: cannot read the line: {raw}")
        key = {"name": pair.group(1), "value": pair.group(2).strip(), "comment": [comment] if comment else []}
        current["keys"].append(key)
        last = key
    return preamble, sections


def number(text):
    text = text.strip()
    if text in CONSTANTS:
        return CONSTANTS[text]
    value = float(text)
    return int(value) if value == int(value) and abs(value) < 1e15 else value


def fmt(value):
    if isinstance(value, float):
        return f"{value:g}"
    if abs(value) >= 100000 and value % 1000 == 0:
        return f"{value:,}"
    return str(value)


def parse_ranges(text):
    """Map 'section.key' to a readable range, from the loader's TableReader calls."""
    tables = {}
    # TableReader lim(top.subtable("limits"), "limits", ...): the path is given.
    for m in re.finditer(r'TableReader (\w+)\(\w+\.subtable\("\w+"\), "([\w.]+)"', text):
        tables[m.group(1)] = m.group(2)
    # TableReader sim = hal.section("sim"): the path is the parent's plus the key.
    parents = {m.group(1): (m.group(2), m.group(3))
               for m in re.finditer(r'TableReader (\w+) = (\w+)\.section\("(\w+)"\)', text)}

    def path(var, depth=0):
        if var in tables:
            return tables[var]
        if var == "top":
            return ""
        if var not in parents or depth > 8:
            return None
        parent, key = parents[var]
        above = path(parent, depth + 1)
        return None if above is None else (f"{above}.{key}" if above else key)

    for var in parents:
        found = path(var)
        if found:
            tables[var] = found
    ranges = {}
    number_call = re.compile(r'(\w+)\.number\("(\w+)",[^;]*?\b(closed|zero_or)\(([^,]+),([^,]+),\s*"([^"]*)"\)\)')
    for m in number_call.finditer(text):
        var, key, kind, lo, hi, unit = m.groups()
        if var not in tables:
            continue
        span = f"{fmt(number(lo))} to {fmt(number(hi))}" + (f" {unit}" if unit else "")
        ranges[f"{tables[var]}.{key}"] = ("0 (off), or " if kind == "zero_or" else "") + span
    integer_call = re.compile(r'(\w+)\.integer\("(\w+)",\s*[^,]+,\s*([^,]+),\s*([^)]+?)\);')
    for m in integer_call.finditer(text):
        var, key, lo, hi = m.groups()
        if var not in tables:
            continue
        ranges[f"{tables[var]}.{key}"] = f"whole number, {fmt(number(lo))} to {fmt(number(hi))}"
    # Inline tables ({ ... }) are read by one function per kind; their fields' ranges.
    for function, keys in (("read_analog_point", ("hal.modbus_io.sensor", "hal.modbus_io.valve")),
                           ("read_comedi_channel", ("hal.comedi.sensor", "hal.comedi.valve"))):
        body = re.search(r"void " + function + r"\(.*?\n}\n", text, re.S)
        if not body:
            continue
        fields = []
        for m in re.finditer(r'\w+\.number\("(\w+)",[^;]*?\b(closed|zero_or)\(([^,]+),([^,]+),\s*"([^"]*)"\)\)', body.group(0)):
            fields.append(f"{m.group(1)} {fmt(number(m.group(3)))} to {fmt(number(m.group(4)))} {m.group(5)}".rstrip())
        for m in re.finditer(r'\w+\.integer\("(\w+)",\s*[^,]+,\s*([^,]+),\s*([^)]+?)\);', body.group(0)):
            fields.append(f"{m.group(1)} {fmt(number(m.group(2)))} to {fmt(number(m.group(3)))}")
        for key in keys:
            if fields:
                ranges[key] = "; ".join(fields)
    return ranges


def cell(text):
    """A table cell: | escaped, and < > outside code spans, so that <token> is shown."""
    parts = text.replace("|", "\\|").split("`")
    for i in range(0, len(parts), 2):
        parts[i] = parts[i].replace("<", "&lt;").replace(">", "&gt;")
    return "`".join(parts)


def join_comment(parts):
    text = " ".join(p for p in parts if p)
    text = re.sub(r"\s*\.\.\.\s*\.\.\.\s*", " ... ", text)
    for old, new in REWRITES:
        text = text.replace(old, new)
    return text.strip()


def render(config_text, loader_text):
    preamble, sections = parse_config(config_text)
    ranges = parse_ranges(loader_text)
    out = [
        "# Configuration reference",
        "",
        "<!-- Generated by scripts/config-reference.py from config/epa.toml and",
        "     src/config/appliance_config.cpp. Do not edit: edit those files and run the script.",
        "     The test docs.config_reference fails when this file is stale. -->",
        "",
        "Every key of `config/epa.toml` (`epa-config/1`), section by section, with its shipped",
        "default, the range `epa serve` accepts, and the comment the file gives it. How to use the",
        "file is in [configuration.md](configuration.md).",
        "",
    ]
    for line in preamble:
        out.append(f"> {line}" if line else ">")
    out.append("")
    for section in sections:
        name = section["name"]
        out.append(f"## [{name}]")
        out.append("")
        intro = join_comment(section["comment"])
        if intro:
            out.append(intro[0].upper() + intro[1:] + ("" if intro.endswith(".") else "."))
            out.append("")
        notes = join_comment(section["notes"])
        if notes:
            out.append(notes)
            out.append("")
        if section["keys"]:
            out.append("| key | default | accepted | what |")
            out.append("| --- | --- | --- | --- |")
            for key in section["keys"]:
                accepted = ranges.get(f"{name}.{key['name']}", "")
                out.append(
                    f"| `{key['name']}` | `{cell(key['value'])}` | {cell(accepted)} | {cell(join_comment(key['comment']))} |"
                )
            out.append("")
    return "\n".join(out).rstrip() + "\n"


def main(argv):
    check = "--check" in argv[1:]
    unknown = [a for a in argv[1:] if a != "--check"]
    if unknown:
        print(f"usage: {argv[0]} [--check]", file=sys.stderr)
        return 2
    loader = LOADER.read_text(encoding="utf-8") if LOADER.exists() else ""  # ranges are left blank without it
    wanted = render(CONFIG.read_text(encoding="utf-8"), loader)
    if not check:
        OUTPUT.write_text(wanted, encoding="utf-8")
        print(f"wrote {OUTPUT.relative_to(ROOT)}")
        return 0
    have = OUTPUT.read_text(encoding="utf-8") if OUTPUT.exists() else ""
    if have == wanted:
        print(f"{OUTPUT.relative_to(ROOT)} is current")
        return 0
    rel = str(OUTPUT.relative_to(ROOT))
    diff = difflib.unified_diff(have.splitlines(), wanted.splitlines(), rel + " (committed)",
                                rel + " (from config/epa.toml)", lineterm="", n=1)
    print(f"{rel} is stale: run scripts/config-reference.py and commit the result. The difference:")
    for line in list(diff)[:60]:
        print(line)
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
