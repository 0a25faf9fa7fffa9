#include "modbus/point_catalog.hpp"

#include <limits>
#include <string>

namespace epa::modbus {

namespace {

using Ctx = PointContext;
double b(bool v) { return v ? 1.0 : 0.0; }
double coefficient(const std::array<double, control::kMaxLawOrder + 1>& c, std::uint8_t degree, int i) {
  return i <= degree ? c[static_cast<std::size_t>(i)] : 0.0;
}

// Names of the array points, kept alive for the string_views in the catalog.
const std::vector<std::string>& coefficient_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (char p : {'F', 'G', 'H'})
      for (int i = 0; i <= static_cast<int>(control::kMaxLawOrder); ++i) n.push_back(std::string(1, p) + std::to_string(i));
    return n;
  }();
  return names;
}

std::vector<PointDef> build() {
  using W = WriteEffect;
  std::vector<PointDef> p = {
      // identity and status
      {"version_major", "", "firmware version, major", W::kNone, 0, 0, true, [](const Ctx&, int) { return double(kVersionMajor); }},
      {"version_minor", "", "firmware version, minor", W::kNone, 0, 0, true, [](const Ctx&, int) { return double(kVersionMinor); }},
      {"version_patch", "", "firmware version, patch", W::kNone, 0, 0, true, [](const Ctx&, int) { return double(kVersionPatch); }},
      {"mode", "", "0 stop, 1 run, 2 manual (3 fault: read only; leave it with reset)", W::kMode, 0, 2, true,
       [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.mode)); }},
      {"fault_code", "", "latched fault: 0 none, 1 sensor not finite, 2 sensor out of range, 3 soft limit, 4 I/O errors, "
                         "5 overruns, 6 following error, 7 heartbeat lost, 8 controller fault, 9 store damaged, 10 sensor frozen", W::kNone, 0, 0, true,
       [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.fault)); }},
      {"fault_active", "", "1 while a fault is latched", W::kNone, 0, 0, true, [](const Ctx& c, int) { return b(c.snapshot.mode == runtime::Mode::kFault); }},
      {"controller", "", "0 pp, 1 pp-ngidz, 2 pp-ffidz", W::kController, 0, 2, true,
       [](const Ctx& c, int) { return double(static_cast<int>(c.snapshot.controller)); }},
      {"setpoint_mm", "mm", "position setpoint", W::kSetpoint, 0, 500, false, [](const Ctx& c, int) { return c.snapshot.setpoint_mm; }},
      {"position_mm", "mm", "measured piston position", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.position_mm; }},
      {"error_mm", "mm", "setpoint - position", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.error_mm; }},
      {"sensor_v", "V", "position sensor voltage", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.sensor_v; }},
      {"valve_v", "V", "valve command applied", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.valve_v; }},
      {"controller_output_v", "V", "pole-placement output before dead-zone compensation", W::kNone, 0, 0, false,
       [](const Ctx& c, int) { return c.snapshot.controller_v; }},
      {"manual_valve_v", "V", "valve command in MANUAL (writable in MANUAL only)", W::kManualValve, -10, 10, false,
       [](const Ctx& c, int) { return c.snapshot.manual_valve_v; }},
      {"saturated", "", "1 while the valve command is at its limit", W::kNone, 0, 0, true, [](const Ctx& c, int) { return b(c.snapshot.saturated); }},
      {"io_ok", "", "1 while the DAQ reads and writes succeed", W::kNone, 0, 0, true, [](const Ctx& c, int) { return b(c.snapshot.io_ok); }},
      {"reset", "", "write 1: clear a latched fault (to STOP)", W::kReset, 1, 1, true, [](const Ctx&, int) { return 0.0; }},
      {"heartbeat", "", "the supervising client increments this; if it stops, the appliance faults", W::kHeartbeat, 0, 4294967295.0, true,
       [](const Ctx& c, int) { return double(c.snapshot.heartbeat); }},
      {"record_s", "s", "write N: save the last N seconds as a run file", W::kRecord, 0.1, 3600, false, [](const Ctx&, int) { return 0.0; }},
      {"unlock", "", "write the configured key: tuning registers writable until the unlock timeout", W::kUnlock, 0, 65535, true,
       [](const Ctx&, int) { return 0.0; }},
      {"locked", "", "1 while tuning registers refuse writes", W::kNone, 0, 0, true, [](const Ctx& c, int) { return b(c.server.locked); }},
      {"store_ok", "", "1 while the tuning store saves changes; 0 while its writes fail (disk full, read-only): saved_counter stands still until they succeed", W::kNone, 0, 0, true, [](const Ctx& c, int) { return b(c.server.saving); }},
      {"change_counter", "", "accepted changes since start (Modbus and web); the heartbeat and the unlock key do not count", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.server.change_counter); }},
      {"saved_counter", "", "how many of the accepted changes are on disk: once it reaches the change_counter read after a write, that write survives a crash", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.server.saved_counter); }},
      {"modbus_requests", "", "requests served since start", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.server.requests); }},
      {"modbus_clients", "", "connected Modbus clients", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.server.clients); }},
      // tuning
      {"Ts_s", "s", "sample time", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.Ts; }},
      {"m_r", "", "dead zone right slope", W::kDeadZoneMr, 1e-6, 100, false, [](const Ctx& c, int) { return c.snapshot.tuning.m_r; }},
      {"m_l", "", "dead zone left slope", W::kDeadZoneMl, 1e-6, 100, false, [](const Ctx& c, int) { return c.snapshot.tuning.m_l; }},
      {"b_r", "V", "dead zone right break point", W::kDeadZoneBr, -10, 10, false, [](const Ctx& c, int) { return c.snapshot.tuning.b_r; }},
      {"b_l", "V", "dead zone left break point", W::kDeadZoneBl, -10, 10, false, [](const Ctx& c, int) { return c.snapshot.tuning.b_l; }},
      {"lc_mm", "mm", "FF-IDZ switch-off band l_c", W::kLc, 0, 100, false, [](const Ctx& c, int) { return c.snapshot.tuning.lc_mm; }},
      // last move (NaN: never reached / never moved)
      {"move_number", "", "moves measured since start", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.last_move.number); }},
      {"move_from_mm", "mm", "last move: start", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.last_move.from_mm; }},
      {"move_to_mm", "mm", "last move: setpoint", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.last_move.to_mm; }},
      {"move_rise_s", "s", "last move: rise time 10-90 %", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.last_move.rise_s; }},
      {"move_settling_s", "s", "last move: 2 % settling time", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.last_move.settling_s; }},
      {"move_ess_mm", "mm", "last move: steady-state error", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.last_move.ess_mm; }},
      {"move_overshoot_pct", "%", "last move: overshoot", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.last_move.overshoot_pct; }},
      // loop statistics and counters
      {"loop_wake_p50_us", "us", "scan cycle wake-up latency, median", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.loop.wake_p50_us; }},
      {"loop_wake_p99_us", "us", "scan cycle wake-up latency, 99th percentile", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.loop.wake_p99_us; }},
      {"loop_wake_max_us", "us", "scan cycle wake-up latency, maximum", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.loop.wake_max_us; }},
      {"loop_jitter_p99_us", "us", "scan period jitter, 99th percentile", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.loop.jitter_p99_us; }},
      {"loop_compute_p99_us", "us", "scan cycle compute time, 99th percentile", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.loop.compute_p99_us; }},
      {"loop_overruns", "", "cycles that missed their deadline", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.loop.overruns); }},
      {"cycles", "", "scan cycles since start", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.cycle); }},
      {"uptime_s", "s", "time since start", W::kNone, 0, 0, false, [](const Ctx& c, int) { return c.snapshot.time_s; }},
      {"moves", "", "moves finished since start", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.moves); }},
      {"faults", "", "faults since start", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.faults); }},
      {"io_errors", "", "failed DAQ reads and writes since start", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.io_errors); }},
      {"commands_applied", "", "commands the scan cycle applied", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.commands_applied); }},
      {"commands_rejected", "", "commands the scan cycle refused", W::kNone, 0, 0, true, [](const Ctx& c, int) { return double(c.snapshot.commands_rejected); }},
  };
  const auto& names = coefficient_names();
  for (std::size_t k = 0; k < names.size(); ++k) {
    const int i = static_cast<int>(k % (control::kMaxLawOrder + 1));
    static constexpr std::string_view kWhat[] = {"controller F coefficient of q^-i (F u = H r - G y)",
                                                 "controller G coefficient of q^-i", "controller H coefficient of q^-i"};
    PointDef d{names[k], "", kWhat[k / (control::kMaxLawOrder + 1)], W::kNone, 0, 0, false, nullptr, i};
    switch (k / (control::kMaxLawOrder + 1)) {
      case 0: d.read = [](const Ctx& c, int j) { return coefficient(c.snapshot.tuning.F, c.snapshot.tuning.nF, j); }; break;
      case 1: d.read = [](const Ctx& c, int j) { return coefficient(c.snapshot.tuning.G, c.snapshot.tuning.nG, j); }; break;
      default: d.read = [](const Ctx& c, int j) { return coefficient(c.snapshot.tuning.H, c.snapshot.tuning.nH, j); }; break;
    }
    p.push_back(d);
  }
  return p;
}

}  // namespace

const std::vector<PointDef>& point_catalog() {
  static const std::vector<PointDef> catalog = build();
  return catalog;
}

const PointDef* find_point(std::string_view name) {
  for (const auto& p : point_catalog())
    if (p.name == name) return &p;
  return nullptr;
}

}  // namespace epa::modbus
