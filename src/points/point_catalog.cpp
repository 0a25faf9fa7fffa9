#include "points/point_catalog.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "core/version.hpp"

namespace epa::points {

namespace {

using Ctx = PointContext;
using A = Access;
using P = PointId;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
double b(bool v) { return v ? 1.0 : 0.0; }
double coefficient(const std::array<double, kCoefficients>& c, std::uint8_t degree, int i) {
  return i <= degree ? c[static_cast<std::size_t>(i)] : 0.0;
}

// Names of the indexed points, kept alive for the string_views in the catalog.
const std::vector<std::string>& record_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const char* field : {"target_mm", "speed_mm_s", "window_mm", "controller", "approach"})
      for (std::size_t i = 1; i <= kPositionRecords; ++i) n.push_back("record" + std::to_string(i) + "_" + field);
    return n;
  }();
  return names;
}

constexpr std::string_view kControlBitNames[runtime::kControlBits] = {"start", "halt", "jog_plus", "jog_minus", "control_reset"};
constexpr std::string_view kControlBitText[runtime::kControlBits] = {
    "control word bit 0: rising edge starts the selected record (record_select; 0: the setpoint); needs RUN",
    "control word bit 1: rising edge brakes (halt_decel_mm_s2) and holds where the piston stops",
    "control word bit 2: held, jogs towards larger positions (MANUAL, jog_speed_mm_s); released, brakes",
    "control word bit 3: held, jogs towards smaller positions (MANUAL)",
    "control word bit 4: rising edge clears a latched fault"};
constexpr std::string_view kStatusBitNames[runtime::kStatusBits] = {"ready", "run_enabled", "moving", "in_position", "target_reached",
                                                                    "following_error", "warning", "fault_latched", "ack", "halted",
                                                                    "jogging", "manual_mode", "off_target", "hunting", "health_warning"};
constexpr std::string_view kStatusBitText[runtime::kStatusBits] = {
    "status bit 0: no fault latched and the I/O works",
    "status bit 1: mode RUN (the law holds or moves the axis)",
    "status bit 2: a move, halt or jog is under way (a move ends in position, or standing off target: bit 12)",
    "status bit 3: |target - position| within the window for in_position_time_s (RUN); the target is the last move's, "
    "so a halt short of it reads 0; a target written and not yet taken reads 0 from the write on",
    "status bit 4: the last started move came into position (RUN; cleared by the next start, from its write on)",
    "status bit 5: the piston beyond following_error_mm from the motion it is asked to follow (a speed-limited move's "
    "profile, or for a step the model's planned motion, up to the target) for 0.2 s; the fault follows after following_error_time_s",
    "status bit 6: following error, off target, hunting, a health warning, I/O errors, the store not saving or its disk low",
    "status bit 7: a fault is latched (fault_code)",
    "status bit 8: acknowledge: mirrors the control word's start bit once the loop applied it",
    "status bit 9: the last task was a halt (in_position then says whether it stopped at the move's target)",
    "status bit 10: a jog (or its braking) is under way",
    "status bit 11: mode MANUAL",
    "status bit 12: the move stopped outside its window: the piston has stood within one window's width for standstill_time_s (RUN); "
    "clears if it comes in, or at the next start",
    "status bit 13: the law hunted (a limit cycle about the standing target: the piston came to rest on alternating "
    "sides of it twice within 2 s) under pp, pp-ngidz or pp-ffidz: the valve is held centred where the piston stands (RUN; also a warning); "
    "clears at the next start or target. pp-traj is not held: it arrives while sliding instead",
    "status bit 14: the model-health monitor's verdict is drifting, unexplained or hunting (health_state says which, "
    "health_effect what drifted): a warning, never a fault"};

// Names of the coefficient points (F0..H6), kept alive for the string_views in the catalog.
const std::vector<std::string>& coefficient_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (char p : {'F', 'G', 'H'})
      for (std::size_t i = 0; i < kCoefficients; ++i) n.push_back(std::string(1, p) + std::to_string(i));
    return n;
  }();
  return names;
}

// The fault history's points: what each field of entry i is called and reads.
struct FaultField {
  PointId first;
  std::string_view suffix, unit, what;
  bool integer;
  double (*read)(const Ctx&, int);
};
double empty_or(const runtime::FaultRecord& r, double v) { return r.code == runtime::FaultCode::kNone ? kNaN : v; }
const FaultField kFaultFields[] = {
    {P::kFaultCode0, "code", "", "fault code as fault_code (0: an empty slot)", true,
     [](const Ctx& c, int i) { return double(static_cast<int>(c.status.recent_faults[static_cast<std::size_t>(i)].code)); }},
    {P::kFaultMode0, "mode", "", "the mode it was in before the fault, as mode (an empty slot: no value, 65535 on Modbus)", true,
     [](const Ctx& c, int i) {
       const auto& r = c.status.recent_faults[static_cast<std::size_t>(i)];
       return empty_or(r, double(static_cast<int>(r.mode)));
     }},
    {P::kFaultTime0, "time_s", "s", "when it latched, unix time (an empty slot: no value, 4294967295 on Modbus)", true,
     [](const Ctx& c, int i) {
       const auto& r = c.status.recent_faults[static_cast<std::size_t>(i)];
       return empty_or(r, std::floor(static_cast<double>(r.time_ms) / 1000.0));
     }},
    {P::kFaultPosition0, "position_mm", "mm", "position when it latched (NaN: not known, or an empty slot)", false,
     [](const Ctx& c, int i) { return c.status.recent_faults[static_cast<std::size_t>(i)].position_mm; }},
    {P::kFaultSetpoint0, "setpoint_mm", "mm", "setpoint when it latched (NaN in an empty slot)", false,
     [](const Ctx& c, int i) { return c.status.recent_faults[static_cast<std::size_t>(i)].setpoint_mm; }},
    {P::kFaultValve0, "valve_v", "V", "valve command applied when it latched (NaN in an empty slot)", false,
     [](const Ctx& c, int i) { return c.status.recent_faults[static_cast<std::size_t>(i)].valve_v; }},
};

// Names and descriptions of the fault history's points (fault_0_code ...), kept alive for the
// string_views in the catalog; in PointId order.
const std::vector<std::pair<std::string, std::string>>& fault_history_texts() {
  static const std::vector<std::pair<std::string, std::string>> texts = [] {
    std::vector<std::pair<std::string, std::string>> t;
    for (const FaultField& f : kFaultFields)
      for (std::size_t i = 0; i < kFaultHistoryPoints; ++i)
        t.emplace_back("fault_" + std::to_string(i) + "_" + std::string(f.suffix),
                       "fault history, " + std::string(i == 0 ? "the newest" : std::to_string(i) + " before the newest") + ": " +
                           std::string(f.what));
    return t;
  }();
  return texts;
}

std::vector<PointDef> build() {
  // {id, name, unit, description, access, min, max, integer, audited, read}
  std::vector<PointDef> p = {
      {P::kVersionMajor, "version_major", "", "firmware version, major", A::kRead, 0, 0, true, true, [](const Ctx&, int) { return double(core::kVersionMajor); }},
      {P::kVersionMinor, "version_minor", "", "firmware version, minor", A::kRead, 0, 0, true, true, [](const Ctx&, int) { return double(core::kVersionMinor); }},
      {P::kVersionPatch, "version_patch", "", "firmware version, patch", A::kRead, 0, 0, true, true, [](const Ctx&, int) { return double(core::kVersionPatch); }},
      {P::kMode, "mode", "", "0 stop, 1 run, 2 manual, 4 excite: the identification experiment, from STOP only, back to STOP by itself "
                             "(3 fault: read only; leave it with reset)", A::kWrite, 0, 4, true, true,
       [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.mode)); }},
      {P::kFaultCode, "fault_code", "", "latched fault: 0 none, 1 sensor not finite, 2 sensor out of range, 3 soft limit, 4 I/O errors, "
                                        "5 overruns, 6 following error, 7 heartbeat lost, 8 controller fault, 9 store damaged, 10 sensor frozen "
                                        "(11 model health: in the fault history only, a warning's start, change or end)",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.fault)); }},
      {P::kFaultActive, "fault_active", "", "1 while a fault is latched", A::kRead, 0, 0, true, true,
       [](const Ctx& c, int) { return b(c.snapshot.mode == runtime::Mode::kFault); }},
      {P::kController, "controller", "", "0 pp, 1 pp-ngidz, 2 pp-ffidz, 3 pp-traj", A::kWrite, 0, 3, true, true,
       [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.controller)); }},
      {P::kSetpoint, "setpoint_mm", "mm", "position setpoint", A::kWrite, 0, 500, false, true, [](const Ctx& c, int) { return c.snapshot.setpoint_mm; }},
      {P::kPosition, "position_mm", "mm", "measured piston position", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.position_mm; }},
      {P::kError, "error_mm", "mm", "setpoint - position", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.error_mm; }},
      {P::kSensor, "sensor_v", "V", "position sensor voltage", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.sensor_v; }},
      {P::kValve, "valve_v", "V", "valve command applied", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.valve_v; }},
      {P::kControllerOutput, "controller_output_v", "V", "pole-placement output before dead-zone compensation", A::kRead, 0, 0, false, true,
       [](const Ctx& c, int) { return c.snapshot.controller_v; }},
      {P::kManualValve, "manual_valve_v", "V", "valve command in MANUAL (writable in MANUAL only)", A::kWrite, -10, 10, false, true,
       [](const Ctx& c, int) { return c.snapshot.manual_valve_v; }},
      {P::kSaturated, "saturated", "", "1 while the valve command is at its limit", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return b(c.snapshot.saturated); }},
      {P::kIoOk, "io_ok", "", "1 while the DAQ reads and writes succeed", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return b(c.snapshot.io_ok); }},
      {P::kReset, "reset", "", "write 1: clear a latched fault (to STOP)", A::kWrite, 1, 1, true, true, [](const Ctx&, int) { return 0.0; }},
      {P::kHeartbeat, "heartbeat", "", "the supervising client increments this; if it stops, the appliance faults", A::kWrite, 0, 4294967295.0, true,
       false, [](const Ctx& c, int) { return double(c.snapshot.heartbeat); }},
      {P::kRecord, "record_s", "s", "write N: save the last N seconds as a run file", A::kWrite, 0.1, 3600, false, true, [](const Ctx&, int) { return 0.0; }},
      {P::kUnlock, "unlock", "", "write the configured 64-bit key (key64: 4 registers, most significant first): tuning registers "
                                 "writable for this connection until the unlock timeout or until it closes; after 5 wrong keys the "
                                 "address is refused for a back-off that doubles up to 5 minutes", A::kKey, 0, 0, true, false,
       [](const Ctx&, int) { return 0.0; }},
      // the positioning interface
      {P::kControlWord, "control_word", "", "bits: 0 start (edge), 1 halt (edge), 2 jog_plus, 3 jog_minus (held, MANUAL), "
                                            "4 reset (edge); docs/registers.md", A::kWrite, 0, runtime::kControlWordMask, true, true,
       [](const Ctx& c, int) { return double(c.snapshot.axis.control_word); }},
      {P::kRecordSelect, "record_select", "", "the record a start moves to: 1..32, or 0 for setpoint_mm", A::kWrite, 0,
       double(kPositionRecords), true, true, [](const Ctx& c, int) { return double(c.status.record_select); }},
      {P::kLocked, "locked", "", "1 while tuning registers refuse this connection's writes", A::kRead, 0, 0, true, true,
       [](const Ctx& c, int) { return b(c.status.locked); }},
      {P::kStoreOk, "store_ok", "", "1 while the tuning store saves changes; 0 while its writes fail (disk full, read-only): saved_counter stands still until they succeed",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return b(c.status.saving); }},
      {P::kDiskLow, "disk_low", "", "1 while the store's disk has less free space than [store] min_free_mb: run files are no longer written, and the store may stop saving next (status bit 6 too)",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return b(c.status.disk_low); }},
      {P::kChangeCounter, "change_counter", "", "accepted changes since start (Modbus and web); the heartbeat and the unlock key do not count",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.change_counter); }},
      {P::kSavedCounter, "saved_counter", "", "how many of the accepted changes are on disk: once it reaches the change_counter read after a write, that write survives a crash",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.saved_counter); }},
      {P::kModbusRequests, "modbus_requests", "", "requests served since start", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.requests); }},
      {P::kModbusClients, "modbus_clients", "", "connected Modbus clients", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.clients); }},
      {P::kUnlockFailures, "unlock_failures", "", "refused unlock attempts since start: wrong keys and attempts during a back-off", A::kRead, 0, 0,
       true, true, [](const Ctx& c, int) { return double(c.status.unlock_failures); }},
      // tuning
      {P::kTs, "Ts_s", "s", "sample time", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.Ts; }},
      {P::kMr, "m_r", "", "dead zone right slope", A::kTuning, 1e-6, 100, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.m_r; }},
      {P::kMl, "m_l", "", "dead zone left slope", A::kTuning, 1e-6, 100, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.m_l; }},
      {P::kBr, "b_r", "V", "dead zone right break point", A::kTuning, -10, 10, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.b_r; }},
      {P::kBl, "b_l", "V", "dead zone left break point", A::kTuning, -10, 10, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.b_l; }},
      {P::kLc, "lc_mm", "mm", "FF-IDZ switch-off band l_c", A::kTuning, 0, 100, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.lc_mm; }},
      {P::kTrajSpeedFraction, "traj_speed_fraction", "", "pp-traj: top speed of its profile, as a fraction of the model's at the valve limit",
       A::kTuning, 0.05, 1, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.traj_speed_fraction; }},
      {P::kTrajBandwidth, "traj_bandwidth_rad_s", "rad/s", "pp-traj: crossover of its feedback (what corrects the model's errors)",
       A::kTuning, 0.5, 30, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.traj_bandwidth_rad_s; }},
      {P::kTrajHoldBand, "traj_hold_band_mm", "mm", "pp-traj: once arrived, the valve is held at 0 V within this error",
       A::kTuning, 0, 5, false, true, [](const Ctx& c, int) { return c.snapshot.tuning.traj_hold_band_mm; }},
      // the excitation experiment: settings for the next EXCITE (a running one keeps its own)
      {P::kExciteSeed, "excite_seed", "", "excitation: seed of the pseudo-random pulses (the same seed, the same signal)", A::kTuning, 0,
       4294967295.0, true, true, [](const Ctx& c, int) { return double(c.snapshot.excitation.seed); }},
      {P::kExciteAmplitudeMin, "excite_amplitude_min_v", "V", "excitation: smallest pulse level (at most excite_amplitude_max_v)", A::kTuning, 0.01,
       10, false, true, [](const Ctx& c, int) { return c.snapshot.excitation.amplitude_min_v; }},
      {P::kExciteAmplitudeMax, "excite_amplitude_max_v", "V", "excitation: largest valve command (either sign) of its ramps and pulses", A::kTuning, 0.01, 10,
       false, true, [](const Ctx& c, int) { return c.snapshot.excitation.amplitude_max_v; }},
      {P::kExciteDuration, "excite_duration_s", "s", "excitation: length of the experiment; then STOP by itself", A::kTuning, 1, 600, false, true,
       [](const Ctx& c, int) { return c.snapshot.excitation.duration_s; }},
      {P::kExciteLeft, "excite_left_s", "s", "excitation: time left of the running experiment (0 outside EXCITE)", A::kRead, 0, 0, false, true,
       [](const Ctx& c, int) { return c.snapshot.excitation_left_s; }},
      // commissioning (excite, identify, design, verify, deploy or roll back): the service's state
      {P::kCommissionCommand, "commission_command", "", "1 start commissioning with the default spec, 2 abort it (after unlock); reads 0",
       A::kTuning, 1, 2, true, true, [](const Ctx&, int) { return 0.0; }},
      {P::kCommissionStage, "commission_stage", "", "0 idle, 1 exciting, 2 identifying, 3 designing, 4 simulating, 5 saving, "
                                                    "6 verifying on the axis, 7 done",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.commission.stage); }},
      {P::kCommissionVerdict, "commission_verdict", "", "of the last commissioning run: 0 none, 1 deployed, 2 rolled back, 3 aborted",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.commission.verdict); }},
      {P::kCommissionProgress, "commission_progress_pct", "%", "commissioning: share of the sequence done", A::kRead, 0, 0, false, true,
       [](const Ctx& c, int) { return c.status.commission.percent; }},
      // the model-health monitor (appliance/health_monitor.hpp): its verdict on the axis against the running set's model
      {P::kHealthCommand, "health_command", "", "1 retake the model-health baseline (after unlock): the next moves are learnt as the axis's normal; reads 0",
       A::kTuning, 1, 1, true, true, [](const Ctx&, int) { return 0.0; }},
      {P::kHealthState, "health_state", "", "model health: 0 off (no stick-slip model, or [health] enabled = false), 1 learning its baseline, 2 ok, "
                                            "3 drifting (health_effect names the change), 4 unexplained (the axis left its model, no single effect explains it), "
                                            "5 hunting (a limit cycle about a standing target); 3-5 warn (status bit 14), never fault",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(static_cast<int>(c.status.health.state)); }},
      {P::kHealthEffect, "health_effect", "", "model health, drifting: what changed, named as by epa diagnose: 0 none, 1 static_friction, "
                                              "2 gain_change (supply, valve gain), 3 deadzone_shift (valve overlap), 4 valve_lag (spool), 5 input_delay",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(static_cast<int>(c.status.health.effect)); }},
      {P::kHealthValue, "health_value", "", "model health, drifting: the effect's model term now (static_friction: breakaway wind-up mm; "
                                            "gain_change: mm/s per V, or as a supply the air spring's frequency rad/s; deadzone_shift: right break point V; valve_lag: s; input_delay: samples); NaN otherwise",
       A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.health.value; }},
      {P::kHealthCommissioned, "health_commissioned", "", "model health, drifting: the same term of the commissioned model; NaN otherwise",
       A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.health.commissioned; }},
      {P::kHealthRatio, "health_ratio", "", "model health, drifting: health_value / health_commissioned (friction doubled: 2); NaN otherwise",
       A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.health.ratio; }},
      {P::kHealthMovesSinceOnset, "health_moves_since_onset", "", "model health, drifting or unexplained: moves since the first that showed it",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.health.moves_since_onset); }},
      {P::kHealthMovesSeen, "health_moves_seen", "", "model health: moves judged since the model was set or the baseline retaken",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.health.moves_seen); }},
      // last move (NaN: does not apply to how it ended, core/move_metrics.hpp)
      {P::kMoveNumber, "move_number", "", "moves measured since start", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.last_move.number); }},
      {P::kMoveFrom, "move_from_mm", "mm", "last move: start", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.last_move.from_mm; }},
      {P::kMoveTo, "move_to_mm", "mm", "last move: setpoint", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.last_move.to_mm; }},
      {P::kMoveRise, "move_rise_s", "s", "last move: rise time 10-90 %", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.last_move.rise_s; }},
      {P::kMoveSettling, "move_settling_s", "s", "last move: 2 % settling time", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.last_move.settling_s; }},
      {P::kMoveEss, "move_ess_mm", "mm", "last move: steady-state error", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.last_move.ess_mm; }},
      {P::kMoveOvershoot, "move_overshoot_pct", "%", "last move: overshoot", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.last_move.overshoot_pct; }},
      {P::kMoveEnd, "move_end", "", "last move: how it ended: 0 in position, 1 cut short by a new target, 2 halted (after its braking), "
                                    "3 stopped (mode change), 4 fault, 5 controller switched, 6 timeout (not in position move_window_s "
                                    "after its reference arrived), 7 off target (stood still outside its window); its metrics are over its own samples",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.last_move.end); }},
      // loop statistics and counters
      {P::kLoopWakeP50, "loop_wake_p50_us", "us", "scan cycle wake-up latency, median", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.loop.wake_p50_us; }},
      {P::kLoopWakeP99, "loop_wake_p99_us", "us", "scan cycle wake-up latency, 99th percentile", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.loop.wake_p99_us; }},
      {P::kLoopWakeMax, "loop_wake_max_us", "us", "scan cycle wake-up latency, maximum", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.loop.wake_max_us; }},
      {P::kLoopJitterP99, "loop_jitter_p99_us", "us", "scan period jitter, 99th percentile", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.loop.jitter_p99_us; }},
      {P::kLoopComputeP99, "loop_compute_p99_us", "us", "scan cycle compute time, 99th percentile", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.loop.compute_p99_us; }},
      {P::kLoopOverruns, "loop_overruns", "", "cycles that missed their deadline", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.loop.overruns); }},
      {P::kCycles, "cycles", "", "scan cycles since start", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.cycle); }},
      {P::kUptime, "uptime_s", "s", "time since start", A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.time_s; }},
      {P::kMoves, "moves", "", "moves finished since start", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.moves); }},
      {P::kFaults, "faults", "", "faults since start", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.faults); }},
      {P::kIoErrors, "io_errors", "", "failed DAQ reads and writes since start", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.io_errors); }},
      {P::kCommandsApplied, "commands_applied", "", "commands the scan cycle applied", A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.commands_applied); }},
      {P::kCommandsRejected, "commands_rejected", "", "accepted commands the scan cycle refused after all (the state changed before it applied them)",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.snapshot.commands_rejected); }},
      {P::kLastCommandRefusal, "last_command_refusal", "", "why the scan cycle last refused a command: 0 none, 1 setpoint out of range, 2 manual valve out of range, "
                                                            "3 not in MANUAL, 4 fault latched, 5 FAULT not settable, 6 recorder busy, 7 record seconds out of range, "
                                                            "8 EXCITE not from STOP, 9 piston outside the excitation's guard lines, 10 excitation settings invalid, "
                                                            "11 the law cannot use the tuning set's model, 12 start outside RUN, 13 jog outside MANUAL",
       A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.last_refusal)); }},
  };
  // Positioning: the control bits as coils, the status word and its bits, reference and speed.
  // (Inserted at their ids' places: the catalog is in PointId order.)
  std::vector<PointDef> positioning;
  for (int i = 0; i < runtime::kControlBits; ++i)
    positioning.push_back({indexed_id(P::kControlBit0, static_cast<std::size_t>(i)), kControlBitNames[i], "", kControlBitText[i], A::kWrite,
                           0, 1, true, true, [](const Ctx& c, int bit) { return b(c.snapshot.axis.control_word & (1u << bit)); }, i});
  positioning.push_back({P::kStatusWord, "status_word", "", "bits 0 ready, 1 enabled, 2 moving, 3 in_position, 4 target_reached, "
                                                              "5 following_error, 6 warning, 7 fault, 8 ack, 9 halted, 10 jogging, 11 manual, "
                                                              "12 off_target, 13 hunting, 14 health_warning",
                         A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(status_word(c.snapshot, c.status)); }});
  for (int i = 0; i < runtime::kStatusBits; ++i)
    positioning.push_back({indexed_id(P::kStatusBit0, static_cast<std::size_t>(i)), kStatusBitNames[i], "", kStatusBitText[i], A::kRead, 0, 0,
                           true, true, [](const Ctx& c, int bit) { return b(status_word(c.snapshot, c.status) & (1u << bit)); }, i});
  positioning.push_back({P::kReference, "reference_mm", "mm", "what the control law follows: the target, or a halt's or jog's braking path",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.snapshot.axis.reference_mm; }});
  positioning.push_back({P::kSpeed, "speed_mm_s", "mm/s", "measured piston speed (low-pass 20 ms)", A::kRead, 0, 0, false, true,
                         [](const Ctx& c, int) { return c.snapshot.axis.speed_mm_s; }});
  positioning.push_back({P::kConfiguredSoftMin, "configured_soft_min_mm", "mm", "[limits] soft_min_mm: the piston below this in RUN, MANUAL or EXCITE faults",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.soft_min_mm; }});
  positioning.push_back({P::kConfiguredSoftMax, "configured_soft_max_mm", "mm", "[limits] soft_max_mm: the piston above this in RUN, MANUAL or EXCITE faults",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.soft_max_mm; }});
  positioning.push_back({P::kConfiguredSetpointMin, "configured_setpoint_min_mm", "mm",
                         "the smallest setpoint or record target a write may carry ([limits] setpoint_min_mm, narrowed by the register map)",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.setpoint_min_mm; }});
  positioning.push_back({P::kConfiguredSetpointMax, "configured_setpoint_max_mm", "mm",
                         "the largest setpoint or record target a write may carry ([limits] setpoint_max_mm, narrowed by the register map)",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.setpoint_max_mm; }});
  positioning.push_back({P::kConfiguredInPositionWindow, "configured_in_position_window_mm", "mm",
                         "[motion] in_position_window_mm: in position within this of the target (a record may set its own)",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.in_position_window_mm; }});
  positioning.push_back({P::kConfiguredFollowingError, "configured_following_error_mm", "mm",
                         "[limits] following_error_mm: the following error's limit (status bit 5)",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.following_error_mm; }});
  positioning.push_back({P::kConfiguredFollowingTime, "configured_following_error_time_s", "s",
                         "[limits] following_error_time_s: beyond the limit this long faults (0: off)",
                         A::kRead, 0, 0, false, true, [](const Ctx& c, int) { return c.status.limits.following_error_time_s; }});
  positioning.push_back({P::kRunningController, "running_controller", "",
                         "the law stepping now (as controller): the selected one, a record's own law during its move, "
                         "or pp-traj braking a halt or a jog",
                         A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.running_law)); }});
  const auto after_select = std::find_if(p.begin(), p.end(), [](const PointDef& d) { return d.id == P::kRecordSelect; }) + 1;
  p.insert(after_select, positioning.begin(), positioning.end());

  p.push_back({P::kFaultHistoryCount, "fault_history_count", "", "faults (and model-health warnings, code 11) recorded since the tuning store was created (the history keeps the newest 64)",
               A::kRead, 0, 0, true, true, [](const Ctx& c, int) { return double(c.status.fault_history_count); }});
  const auto& fault_texts = fault_history_texts();
  for (std::size_t k = 0; k < fault_texts.size(); ++k) {
    const FaultField& f = kFaultFields[k / kFaultHistoryPoints];
    const int i = static_cast<int>(k % kFaultHistoryPoints);
    p.push_back({fault_history_id(f.first, static_cast<std::size_t>(i)), fault_texts[k].first, f.unit, fault_texts[k].second,
                 A::kRead, 0, 0, f.integer, true, f.read, i});
  }

  // The position-record table.
  static constexpr std::string_view kRecordText[] = {
      "position record: target", "position record: speed limit (0: none, the law's own step response)",
      "position record: in-position window (0: [motion] in_position_window_mm)",
      "position record: law (0 pp, 1 pp-ngidz, 2 pp-ffidz, 3 pp-traj; 255 the running one)",
      "position record: side pp-traj's sliding arrival comes from (0 the near side: never past the target; 1 from below, "
      "2 from above: from that side even when the piston stands on the other, passing the target by up to one approach length)"};
  static constexpr double kRecordMax[] = {10000.0, 10000.0, 100.0, double(kKeepController), 2.0};
  static constexpr std::string_view kRecordUnit[] = {"mm", "mm/s", "mm", "", ""};
  const auto& records = record_names();
  for (std::size_t k = 0; k < records.size(); ++k) {
    const std::size_t field = k / kPositionRecords;
    PointDef d{indexed_id(P::kRecordTarget0, k), records[k], kRecordUnit[field], kRecordText[field], A::kTuning,
               field == 0 ? -10000.0 : 0.0, kRecordMax[field], field >= 3, true, nullptr, static_cast<int>(k)};
    d.read = [](const Ctx& c, int j) {
      RecordField f;
      record_field(indexed_id(P::kRecordTarget0, static_cast<std::size_t>(j)), f);
      return record_value(c.status.records[f.record], f.kind);
    };
    p.push_back(d);
  }

  const auto& names = coefficient_names();
  static constexpr std::string_view kWhat[] = {"controller F coefficient of q^-i (F u = H r - G y)", "controller G coefficient of q^-i",
                                               "controller H coefficient of q^-i"};
  for (std::size_t k = 0; k < names.size(); ++k) {
    const int i = static_cast<int>(k % kCoefficients);
    PointDef d{static_cast<PointId>(index(PointId::kF0) + k), names[k], "", kWhat[k / kCoefficients], A::kRead, 0, 0, false, true, nullptr, i};
    switch (k / kCoefficients) {
      case 0: d.read = [](const Ctx& c, int j) { return coefficient(c.snapshot.tuning.F, c.snapshot.tuning.nF, j); }; break;
      case 1: d.read = [](const Ctx& c, int j) { return coefficient(c.snapshot.tuning.G, c.snapshot.tuning.nG, j); }; break;
      default: d.read = [](const Ctx& c, int j) { return coefficient(c.snapshot.tuning.H, c.snapshot.tuning.nH, j); }; break;
    }
    p.push_back(d);
  }
  return p;
}

const std::vector<PointDef>& catalog() {
  static const std::vector<PointDef> c = [] {
    auto p = build();
    // In PointId order, one definition each: point(id) is an index.
    for (std::size_t i = 0; i < p.size(); ++i)
      if (index(p[i].id) != i) std::abort();
    if (p.size() != kPointCount) std::abort();
    return p;
  }();
  return c;
}

}  // namespace

std::uint16_t status_word(const runtime::Snapshot& s, bool store_well, bool health_warning) {
  using namespace runtime;
  const bool fault = s.mode == Mode::kFault;
  const bool warning = s.axis.following_error || s.axis.off_target || s.axis.hunting || health_warning || !s.io_ok || !store_well;
  const bool bits[kStatusBits] = {!fault && s.io_ok, s.mode == Mode::kRun, s.axis.moving, s.axis.in_position, s.axis.target_reached,
                                  s.axis.following_error, warning, fault, s.axis.ack, s.axis.halted, s.axis.jogging, s.mode == Mode::kManual,
                                  s.axis.off_target, s.axis.hunting, health_warning};
  std::uint16_t w = 0;
  for (int i = 0; i < kStatusBits; ++i)
    if (bits[i]) w = static_cast<std::uint16_t>(w | (1u << i));
  return w;
}

std::uint16_t status_word(const runtime::Snapshot& s, const InterfaceStatus& status) {
  return status_word(s, status.saving && !status.disk_low, health_warns(status.health.state));
}

std::span<const PointDef> point_catalog() { return catalog(); }
const PointDef& point(PointId id) { return catalog()[index(id)]; }
std::string_view name(PointId id) { return point(id).name; }

const PointDef* find_point(std::string_view name) {
  for (const auto& p : catalog())
    if (p.name == name) return &p;
  return nullptr;
}

}  // namespace epa::points
