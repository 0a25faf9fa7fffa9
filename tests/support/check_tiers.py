"""Every ctest entry has exactly one tier label: unit, process or realtime (docs/dev/testing.md).

    python3 check_tiers.py CTEST BUILD_DIR

Lists each test with no tier or more than one, with the labels it has, and exits 1 if there is any;
a test added without a tier fails here. Reads the registered tests with `ctest --show-only=json-v1`.
"""
import json
import subprocess
import sys

TIERS = ("unit", "process", "realtime")


def main(argv):
    if len(argv) != 3:
        print("usage: check_tiers.py CTEST BUILD_DIR", file=sys.stderr)
        return 2
    ctest, build_dir = argv[1], argv[2]
    out = subprocess.run([ctest, "--test-dir", build_dir, "--show-only=json-v1"], check=True,
                         capture_output=True, text=True).stdout
    tests = json.loads(out)["tests"]
    wrong = []
    counts = dict.fromkeys(TIERS, 0)
    for test in tests:
        labels = []
        for prop in test.get("properties", []):
            if prop["name"] == "LABELS":
                labels = prop["value"]
        tiers = [label for label in labels if label in TIERS]
        if len(tiers) == 1:
            counts[tiers[0]] += 1
        else:
            wrong.append((test["name"], labels))
    for name, labels in wrong:
        print(f"NO SINGLE TIER: {name}: labels {labels or 'none'} (give it one of {', '.join(TIERS)}: tests/CMakeLists.txt)")
    print(f"{len(tests)} tests: " + ", ".join(f"{counts[t]} {t}" for t in TIERS) + f", {len(wrong)} without exactly one tier")
    if not tests:
        print("no tests listed: the check saw nothing")
        return 1
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
