#!/usr/bin/env python3
"""Commissioning over two processes: `epa plant-server --plant physics` with hidden
perturbations (the valve's gain x0.8 through its orifice, the spool overlap shifted +0.2 V) behind a
simulated remote I/O module, `epa serve --hal modbus-io` in real time, and `epa commission` driving
the appliance over HTTP, unattended, with a shortened excitation.

    commission_test.py <epa binary> <source dir>

Checks, each printed with its figures:
  * deployed: `epa commission` with pp-traj and the default limits (1 mm, 5 %) exits 0 with verdict
    "deployed", the new set is the running and the stored active set; then moves of 25-200 mm in
    both directions, commanded over HTTP like an HMI would, end within 1 mm with overshoot <= 5 %,
    and with less overshoot than the paper's tuning (the shipped one, whose model knows no
    stick-slip: its first move hunts before it falls back to arriving while sliding) on the same
    rig before;
  * a verification limit the axis cannot meet (e_ss <= 0.02 mm with NG-IDZ), commissioned on a
    second rig and appliance alongside the first: exit 2, verdict "rolled-back" before the axis
    moves with it (the simulation on the identified stick-slip model already ends 0.5-1 mm off)
    or at the first move, or at identification (which can refuse an experiment); the previous set
    runs again and is still the stored active set, a switch to the new set and back is in the
    audit trail, and the valve command never left its +-5 V limits;
  * a wrong spec is refused before anything moves (HTTP 400, exit 1).
Under the sanitizers (EPA_SANITIZER_RUN=1, set by the asan test preset) the run ends after the
deployment's checks: it has reached every part of the appliance the rest does (excitation,
identification, design, simulation, the switch to the new set and the store), and the sanitizers
judge memory and undefined behaviour, not figures; the HMI moves after it and the roll-back are
behaviour, judged by the release run (about 140 of 350 s under ASan). For the same reason a
deployment rolled back there for a figure missed on the axis (the loop runs late under ASan) is
judged by the state it leaves: the previous set running and stored active, the roll-back audited.
Exit 1 on any failure. A run that failed while the machine itself stalled
(tests/support/stall_monitor.py) is run once more; failing again on a machine as stalled, it has
no verdict: exit 77, which ctest reports as skipped.
"""
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support"))
from epa_appliance import Appliance, free_port, stop_process  # noqa: E402
from stall_monitor import SKIP_RETURN_CODE, StallMonitor  # noqa: E402

TOKEN = "0nckvUtg9V7xrBbM-fiPztEj"
SANITIZER_RUN = os.environ.get("EPA_SANITIZER_RUN") == "1"
FAILURES = []


def check(ok, what):
    print(("ok    " if ok else "FAIL  ") + what, flush=True)
    if not ok:
        FAILURES.append(what)


class PlantServer:
    """`epa plant-server --plant physics`; its output goes to a file (a pipe nobody reads would fill
    and stop it)."""

    def __init__(self, epa, physics_config, folder, name):
        self.port = free_port()
        self.log_path = os.path.join(folder, f"{name}-plant-server.log")
        self.log = open(self.log_path, "w")
        self.proc = subprocess.Popen([epa, "plant-server", "--plant", "physics", "--physics-config", physics_config, "--port",
                                      str(self.port), "--initial-position", "250", "--noise", "0.05", "--seed", "7",
                                      "--realtime-priority", "70"],
                                     stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and "listening" not in open(self.log_path).read():
            if self.proc.poll() is not None:
                break
            time.sleep(0.05)
        if "listening" not in open(self.log_path).read():
            raise RuntimeError(f"plant-server did not start: {open(self.log_path).read()}")

    def stop(self):
        stop_process(self.proc)
        self.log.close()


def http(app, method, path, body=None):
    req = urllib.request.Request(f"http://127.0.0.1:{app.web_port}{path}", method=method,
                                 data=json.dumps(body).encode() if body is not None else None,
                                 headers={"Authorization": f"Bearer {TOKEN}", "Content-Type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            return r.status, json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, json.loads(e.read() or b"null")


def commission(epa, app, spec, folder, name):
    spec_path = os.path.join(folder, f"{name}-spec.json")
    with open(spec_path, "w") as f:
        json.dump(spec, f)
    out, report = os.path.join(folder, f"{name}.json"), os.path.join(folder, f"{name}.html")
    t0 = time.monotonic()
    r = subprocess.run([epa, "commission", "--url", f"http://127.0.0.1:{app.web_port}", "--token", TOKEN, "--spec", spec_path,
                        "--json", out, "--report", report, "--poll", "0.5", "--timeout", "600"],
                       capture_output=True, text=True, timeout=700)
    took = time.monotonic() - t0
    outcome = json.load(open(out)) if os.path.exists(out) else None
    return r, outcome, report, took


def move(app, target_mm, hold_s):
    """RUN to target over HTTP; samples the position from /api/status until hold_s has passed."""
    start = http(app, "GET", "/api/status")[1]["position_mm"]
    code, answer = http(app, "POST", "/api/points", {"setpoint_mm": target_mm, "mode": 1})
    if code != 200:
        status = http(app, "GET", "/api/status")[1]
        raise RuntimeError(f"move to {target_mm} mm refused: HTTP {code} {answer}; the appliance is in mode {status['mode']}, "
                           f"fault {status['fault']}")
    positions = []
    t_end = time.monotonic() + hold_s
    while time.monotonic() < t_end:
        positions.append(http(app, "GET", "/api/status")[1]["position_mm"])
        time.sleep(0.02)
    final = sum(positions[-10:]) / 10
    span = target_mm - start
    peak = max(positions) if span > 0 else min(positions)
    overshoot = max(0.0, (peak - target_mm) / span * 100.0) if span > 0 else max(0.0, (target_mm - peak) / -span * 100.0)
    return start, final, overshoot


HMI_TARGETS = (225, 275, 175, 275, 125, 325, 250, 50, 250, 450)  # moves of 25-200 mm both ways


def hmi_moves(app):
    """The same moves an HMI would command, each held 5 s (a retry of pp-traj's sliding arrival
    takes about 1 s): [(start, target, final, overshoot)]."""
    out = []
    for target in HMI_TARGETS:
        start, final, overshoot = move(app, target, 5.0)
        out.append((start, target, final, overshoot))
    http(app, "POST", "/api/mode", {"mode": "stop"})
    return out


def summary(moves):
    errors = [abs(final - target) for _, target, final, _ in moves]
    return (f"|error| {min(errors):.2f}-{max(errors):.2f} mm (mean {sum(errors) / len(errors):.2f}), "
            f"{sum(e <= 1.0 for e in errors)} of {len(errors)} within 1 mm, overshoot up to {max(m[3] for m in moves):.1f} %")


def start_rig(epa, src, folder, name):
    """A rig (`epa plant-server`, which differs from the built-in defaults in ways the appliance is
    not told) and the appliance that drives it over Modbus: (plant, app)."""
    physics = os.path.join(folder, f"{name}.toml")
    with open(physics, "w") as f:
        f.write('schema = "epa-pneumatic/1"\n[valve]\norifice_area_mm2 = 3.2\noverlap_pos_v = 1.4\noverlap_neg_v = -1.5\n')
    plant = PlantServer(epa, physics, folder, name)
    try:
        app = Appliance(epa, os.path.join(src, "registers", "epa.csv"),
                        # 20 ms per request, not the rig default of 2 ms, and 40 late cycles in a row (200 ms)
                        # before an overrun fault, not 10: on a virtual machine, scheduling stalls of 5-10 ms
                        # (18-42 overruns in a test, p99 wake-up 73 us), and up to 89 ms under ASan, would
                        # otherwise fault the axis mid-test; what is tested here is the commissioning: the
                        # fault injection test keeps the strict I/O timing, tests/runtime/faults_test.cpp
                        # the overrun fault.
                        f'[hal]\nbackend = "modbus-io"\n[hal.modbus_io]\nport = {plant.port}\nresponse_timeout_ms = 20\n'
                        '[loop]\nmax_consecutive_overruns = 40\n',
                        web_static_dir=os.path.join(src, "web"), web_extra=f'token = "{TOKEN}"\n')
    except Exception:
        plant.stop()
        raise
    return plant, app


def stored_active_sets(epa, app):
    """The lines of `epa tuning list` that mark the stored active set (they start with `*`)."""
    listing = subprocess.run([epa, "tuning", "--db", app.db, "list"], capture_output=True, text=True).stdout
    return [line for line in listing.splitlines() if line.startswith("*")], listing


def roll_back_run(epa, app, spec, folder):
    """A verification limit no axis meets, commissioned on its own rig: what the checks read after it."""
    out = {"before": http(app, "GET", "/api/status")[1]["store"]["tuning_set"]}
    out["r"], out["outcome"], _, out["took"] = commission(epa, app, spec, folder, "rolled-back")
    out["running"] = http(app, "GET", "/api/status")[1]["store"]["tuning_set"]
    out["active"], _ = stored_active_sets(epa, app)
    out["audit"] = json.dumps(http(app, "GET", "/api/audit")[1])
    out["valves"] = http(app, "GET", "/api/trend")[1].get("valve_v", [])
    return out


def check_previous_set_back(before, running, active, audit):
    """After a roll-back: the previous set runs and is the stored active set; with the audit trail
    (a roll-back after the switch to the new set), the switch and the roll-back are in it."""
    check(running == before, f"the previous set runs again ({running}; before: {before})")
    check(len(active) == 1 and f" {before} " in active[0], f"the stored active set is still the previous one: {active}")
    if audit is not None:
        check("running_tuning_set" in audit and "rolled-back" in audit, "the switch and the roll-back are audited")


def check_roll_back(out):
    outcome, before = out["outcome"], out["before"]
    stage = outcome and outcome["failed_stage"]
    check(out["r"].returncode == 2 and outcome and outcome["verdict"] == "rolled-back" and stage in ("verifying", "simulating", "identifying"),
          f"a limit the axis cannot meet: exit 2, verdict rolled-back at stage {stage} in {out['took']:.0f} s "
          f"({outcome and outcome['reason']})")
    check_previous_set_back(before, out["running"], out["active"], out["audit"] if stage == "verifying" else None)
    valves = out["valves"]
    check(valves and max(abs(v) for v in valves) <= 5.0 + 1e-9,
          f"the valve never left +-5 V (max |u| {max(abs(v) for v in valves) if valves else 'n/a'} V over the trend)")


def run_once(epa, src):
    folder = tempfile.mkdtemp(prefix="epa-commission-test.")
    # The default limits with pp-traj: identification finds that a stick-slip model describes this
    # rig, so pp-traj arrives while sliding (README, pp-traj). The verification moves cover the
    # sizes the HMI moves below command, both ways (100-200 mm, then -25 and +50 mm: a short
    # move is where a breakaway would overshoot). A move that needs a retry takes 2-3 s, so each
    # is held 6 s (the metrics read the last 2 s) and settling is not judged.
    base = {"excitation_runs": 2, "excitation_s": 40, "seed": 3, "controller": "pp-traj", "settling_s": 0.3,
            "overshoot_pct": 0, "moves_mm": [150, 350, 250, 225, 275], "move_hold_s": 6,
            "limits": {"ess_mm": 1, "overshoot_pct": 5, "overshoot_mm": 0, "settling_s": 0}}
    # A verification limit the axis cannot meet: on the axis the mean |error| over 2 s cannot fall
    # below the sensor noise's 0.04 mm, so e_ss <= 0.02 mm fails at the first move. Since the
    # simulation runs on the stick-slip model that describes this rig, where NG-IDZ already stops
    # 0.5-1 mm off, it usually rolls back before the new set reaches the axis (on a Hammerstein
    # model, where NG-IDZ ends within 0.01 mm, it rolled back at the first move). Identification can
    # also refuse these runs (a side of the dead zone not identified): then the roll-back comes
    # before the axis, which the checks hold as well. It runs on a second rig of its own, alongside
    # the first (its real-time wait is most of the run, and the test runs alone: 300 s one after
    # the other, about 220 s side by side); under the sanitizers it is left to the release run.
    roll_back_spec = dict(base, controller="pp-ngidz", limits={"ess_mm": 0.02, "overshoot_pct": 15, "settling_s": 0}, name="rig-2")
    rigs, roll_back, roll_back_error = [], {}, []
    try:
        rigs.append(start_rig(epa, src, folder, "rig-a"))
        app = rigs[0][1]
        if not SANITIZER_RUN:
            rigs.append(start_rig(epa, src, folder, "rig-b"))

            def run_roll_back():
                try:
                    roll_back.update(roll_back_run(epa, rigs[1][1], roll_back_spec, folder))
                except Exception as e:  # noqa: BLE001 -- reported by the main thread
                    roll_back_error.append(f"{type(e).__name__}: {e}")
            roll_back_thread = threading.Thread(target=run_roll_back, daemon=True)
            roll_back_thread.start()

        before = http(app, "GET", "/api/status")[1]["store"]["tuning_set"]
        # Also under the sanitizers: these moves leave the rig where the commissioning starts from
        # (without them, an ASan run identified the Hammerstein model and rolled back).
        paper_moves = hmi_moves(app)  # the paper's tuning, which the appliance starts with
        print(f"      before commissioning ({before}): {summary(paper_moves)}")

        # A wrong spec: refused before anything moves.
        r, outcome, _, _ = commission(epa, app, dict(base, limits={"ess_mm": -1}), folder, "wrong")
        check(r.returncode == 1 and "limits.ess_mm" in r.stderr, f"a wrong spec is refused naming the key (exit {r.returncode}: {r.stderr.strip()})")

        # Deployed.
        r, outcome, report, took = commission(epa, app, dict(base, name="rig-1"), folder, "deployed")
        deployed = r.returncode == 0 and bool(outcome) and outcome["verdict"] == "deployed"
        # Under the sanitizers the loop runs late (under ASan 146 overruns in a run, wake-ups late
        # by 1.7 ms at the 99th percentile) and the axis's figures are not the product's: a roll-back
        # for a figure missed on the axis is a whole outcome there too, judged below by the state it
        # leaves; the release run judges the figures.
        rolled_back_on_axis = (SANITIZER_RUN and r.returncode == 2 and bool(outcome) and outcome["verdict"] == "rolled-back"
                               and outcome["reason"].startswith("on the axis:"))
        check(deployed or rolled_back_on_axis,
              f"epa commission exits 0 with verdict deployed in {took:.0f} s (exit {r.returncode}; {outcome and outcome['reason']})"
              + (" (under the sanitizers: rolled back for a figure on the axis)" if rolled_back_on_axis else "")
              + ("" if deployed else f"\n{r.stdout}{r.stderr[-2000:]}"))
        if outcome and outcome.get("model"):
            m = outcome["model"]
            print(f"      identified: b_l {m['dead_zone']['b_l']:.3f} V, b_r {m['dead_zone']['b_r']:.3f} V, "
                  f"validation fit {m['validation_fit_pct']:.1f} %")
        for v in (outcome or {}).get("verification", []):
            print(f"      verification {v['from_mm']:.1f} -> {v['to_mm']:.1f} mm: settling {v['settling_s']}, e_ss {v['ess_mm']:.3f} mm, "
                  f"overshoot {v['overshoot_pct']}")
        check(os.path.getsize(report) > 2000 if os.path.exists(report) else False, "the report was written")
        running = http(app, "GET", "/api/status")[1]["store"]["tuning_set"]
        active, listing = stored_active_sets(epa, app)
        if rolled_back_on_axis:
            check_previous_set_back(before, running, active, json.dumps(http(app, "GET", "/api/audit")[1]))
        else:
            check(running == "rig-1", f"the new set runs (running set {running})")
            check(len(active) == 1 and " rig-1 " in active[0], f"the new set is the stored active set: {active or listing}")
        if SANITIZER_RUN:
            print("      under the sanitizers: the HMI moves and the roll-back are left to the release run")
            return
        if outcome and outcome["verdict"] == "deployed":
            # What the verification promised, held by the moves an HMI commands afterwards.
            deployed_moves = hmi_moves(app)
            limits = base["limits"]
            for start, target, final, overshoot in deployed_moves:
                overshoot_mm = overshoot / 100.0 * abs(target - start)
                check(abs(final - target) <= limits["ess_mm"] and (overshoot <= limits["overshoot_pct"] or overshoot_mm <= limits["overshoot_mm"]),
                      f"after deployment: move {start:.1f} -> {target} mm ends {abs(final - target):.2f} mm from its target "
                      f"(spec: {limits['ess_mm']} mm), overshoot {overshoot:.1f} % = {overshoot_mm:.2f} mm "
                      f"(spec: {limits['overshoot_pct']} % or {limits['overshoot_mm']} mm)")
            print(f"      after commissioning (rig-1): {summary(deployed_moves)}")
            # Both end within the window now (the shipped law's fallback keeps a stop inside it);
            # what commissioning adds is the stick-slip model, so no move hunts.
            most_overshoot = lambda moves: max(overshoot for _, _, _, overshoot in moves)
            check(most_overshoot(deployed_moves) < most_overshoot(paper_moves),
                  f"less overshoot than the paper's tuning on the same rig: up to {most_overshoot(deployed_moves):.1f} % "
                  f"against {most_overshoot(paper_moves):.1f} %")

        roll_back_thread.join(timeout=700)
        if roll_back_error or not roll_back:
            check(False, f"the roll-back run on the second rig: {roll_back_error or 'did not end within 700 s'}")
        else:
            check_roll_back(roll_back)
    except Exception as e:  # noqa: BLE001 -- a failure, reported with the appliance's log below
        check(False, f"{type(e).__name__}: {e}")
    finally:
        for plant, app in rigs:
            app.stop()
            plant.stop()
        if FAILURES:  # what the appliances said about it
            for name, (_, app) in zip(("rig-a", "rig-b"), rigs):
                print(f"{name}'s appliance log (faults, commissioning, modes):")
                for line in app.log_text().splitlines():
                    if any(w in line for w in ("FAULT", "commission", "mode ", "refused", "error")):
                        print("   ", line[-220:])


def main():
    epa, src = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    monitor = StallMonitor()
    t0 = time.monotonic()

    def run():
        FAILURES.clear()
        run_once(epa, src)
        return list(FAILURES)

    try:
        # The axis is right to fault when its module falls silent; a stalled machine silences the
        # simulated one, and such a run proves nothing either way.
        _, no_verdict = monitor.judged("the whole test", run)
        print(f"      the machine during the test: {monitor.describe(t0)}")
    finally:
        monitor.stop()
    if no_verdict:
        monitor.not_judged("integration.commission", f"{no_verdict}: it could not run the loop in real time")
        sys.exit(SKIP_RETURN_CODE)
    if FAILURES:
        print(f"{len(FAILURES)} failure(s)")
        sys.exit(1)
    print("all checks passed")


if __name__ == "__main__":
    main()
