#!/usr/bin/env bash
# pp-traj's tables in docs/paper.md, each row from one `epa simulate --json` command:
#   1. Table 1 on the printed model for the four laws (no noise), and pp-traj with 0.1 mm noise;
#   2. robustness of pp-traj: gain x0.8 / x1.2, dead band 0.1 V wider / narrower, 20 ms valve
#      lag, 1-sample delay (the plant differs, the controller keeps the printed model);
#   3. the physics plant (Richer-Hurmuzlu cylinder and valve, stiction), steps up and down from
#      three start positions, with and without a 2-sample delay: pp-ffidz on the paper's tuning and
#      pp-traj on a model identified from the physics plant (epa excite + epa identify, here).
# Prints the acceptance figures beside the limits; "!" marks a figure outside its limit.
#
#   bench/pp_traj_tables.sh [BUILD_DIR=build/release] [fast]
#
# fast (CI's smoke step): the printed-model table only.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
mode=${2:-full}
epa="$build/src/app/epa"
[ -x "$epa" ] || { echo "pp_traj_tables: $epa is not built" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
source bench/physics_axis.sh

sim() {  # sim NAME ARGS...: one epa simulate run, its JSON kept as NAME.json
  local name=$1
  shift
  "$epa" simulate --json "$work/$name.json" "$@" >"$work/$name.log" 2>&1 ||
    { echo "pp_traj_tables: epa simulate $* failed:" >&2; cat "$work/$name.log" >&2; exit 1; }
}

sim nominal --controller pp,pp-ngidz,pp-ffidz,pp-traj
sim noise --controller pp-traj --noise 0.1
if [ "$mode" != fast ]; then
  sim gain08 --controller pp-traj --gain-factor 0.8
  sim gain12 --controller pp-traj --gain-factor 1.2
  sim wider --controller pp-traj --break-point-error 0.1
  sim narrower --controller pp-traj --break-point-error -0.1
  sim lag --controller pp-traj --valve-lag 0.02
  sim delay --controller pp-traj --delay 1
  commission_physics_axis "$epa" "$work" pp_traj_tables  # bench/physics_axis.sh: $work/physics-model.toml
  for start in 100 250 400; do
    for delay in 0 2; do
      sim "phys_ff_${start}_$delay" --plant physics --controller pp-ffidz --start "$start" --steps 25,50,100,-25,-50,-100 --duration 5 --delay "$delay"
      sim "phys_traj_${start}_$delay" --plant physics --controller pp-traj --model "$work/physics-model.toml" --start "$start" \
        --steps 25,50,100,-25,-50,-100 --duration 5 --delay "$delay"
    done
  done
fi

python3 - "$work" "$mode" <<'PY'
import json, sys, os
work, mode = sys.argv[1], sys.argv[2]
def load(name): return json.load(open(os.path.join(work, name + ".json")))["results"]
def f(v, fmt="%.3f"): return "never" if v is None else fmt % v
def mark(ok): return "" if ok else "!"

nominal = load("nominal")
ff = {r["step_mm"]: r for r in nominal if r["controller"] == "pp-ffidz"}
print("Printed model, no noise (epa simulate --controller pp,pp-ngidz,pp-ffidz,pp-traj --json)")
print("%-9s %-6s %8s %8s %8s %8s %5s" % ("law", "step", "rise s", "settle s", "e_ss mm", "OS %", "sc10"))
for r in nominal:
    print("%-9s %-6g %8s %8s %8s %8s %5d" % (r["controller"], r["step_mm"], f(r["rise_s"]), f(r["settling_s"]), f(r["ess_mm"]),
                                          f(r["overshoot_pct"], "%.2f"), r["valve_sign_changes_last_10s"]))
print()
print("pp-traj against its limits (FF-IDZ from the same command)")
for r in nominal:
    if r["controller"] != "pp-traj": continue
    s, peer = r["step_mm"], ff[r["step_mm"]]
    rise_limit = 0.85 * peer["rise_s"] if s <= 50 else (0.30 if s == 100 else 0.40)
    settle_limit = min(0.6 * peer["settling_s"], 0.7)
    ok = lambda v, lim: v is not None and v <= lim
    print("  %g mm: overshoot %s%% (<= 0.5)%s, settling %s s (<= %.3f)%s, e_ss %s mm (<= 0.15)%s, rise %s s (<= %.3f)%s, sign changes %d (0)%s" % (
        s, f(r["overshoot_pct"], "%.2f"), mark(ok(r["overshoot_pct"], 0.5)), f(r["settling_s"]), settle_limit,
        mark(ok(r["settling_s"], settle_limit)), f(r["ess_mm"]), mark(r["ess_mm"] <= 0.15), f(r["rise_s"]), rise_limit,
        mark(ok(r["rise_s"], rise_limit)), r["valve_sign_changes_last_10s"], mark(r["valve_sign_changes_last_10s"] == 0)))
print("With 0.1 mm noise (--noise 0.1): " + ", ".join("%g mm: e_ss %.3f mm (<= 0.2)%s, %d sign changes (<= 2)%s" % (
    r["step_mm"], r["ess_mm"], mark(r["ess_mm"] <= 0.2), r["valve_sign_changes_last_10s"], mark(r["valve_sign_changes_last_10s"] <= 2))
    for r in load("noise")))
if mode == "fast":
    sys.exit(0)
print()
print("Robustness of pp-traj (limits: e_ss <= 0.15 mm, no chatter, overshoot <= 30 %, settling <= 3 s, <= 10 s with the delay)")
print("%-26s %-6s %8s %8s %8s %5s" % ("plant", "step", "OS %", "settle s", "e_ss mm", "sc10"))
for name, label, settle_limit in [("gain08", "gain x0.8", 3), ("gain12", "gain x1.2", 3), ("wider", "dead band 0.1 V wider", 3),
                                  ("narrower", "dead band 0.1 V narrower", 3), ("lag", "20 ms valve lag", 3), ("delay", "1-sample delay", 10)]:
    for r in load(name):
        os_ok = r["overshoot_pct"] is not None and r["overshoot_pct"] <= 30
        st_ok = r["settling_s"] is not None and r["settling_s"] <= settle_limit
        print("%-26s %-6g %7s%1s %7s%1s %7s%1s %4d%1s" % (label, r["step_mm"], f(r["overshoot_pct"], "%.1f"), mark(os_ok), f(r["settling_s"], "%.2f"),
              mark(st_ok), f(r["ess_mm"]), mark(r["ess_mm"] <= 0.15), r["valve_sign_changes_last_10s"], mark(r["valve_sign_changes_last_10s"] <= 2)))
print()
print("Physics plant, steps +-25/50/100 mm from 100, 250, 400 mm (limits for pp-traj: overshoot <= 0.5 mm, e_ss <= 0.3 mm, settling <= 1 s)")
print("%-9s %-6s %-6s %8s %8s %8s %5s" % ("law", "delay", "start", "OS mm", "settle s", "e_ss mm", "sc10"))
for law in ("ff", "traj"):
    for delay in (0, 2):
        worst_os = worst_ess = worst_settle = 0.0
        never = 0; sc = 0; n = 0
        for start in (100, 250, 400):
            for r in load("phys_%s_%d_%d" % (law, start, delay)):
                n += 1
                worst_os = max(worst_os, r["overshoot_mm"] or 0.0)
                worst_ess = max(worst_ess, r["ess_mm"])
                if r["settling_s"] is None: never += 1
                else: worst_settle = max(worst_settle, r["settling_s"])
                sc = max(sc, r["valve_sign_changes_last_10s"])
        print("%-9s %-6d %-6s %8.2f %8s %8.3f %5d   (worst of %d moves; %d never settled)" % (
            "pp-ffidz" if law == "ff" else "pp-traj", delay, "all", worst_os, f(worst_settle, "%.2f"), worst_ess, sc, n, never))
PY
