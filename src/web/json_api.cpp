#include "web/json_api.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "control/controller_kind.hpp"
#include "core/move_metrics.hpp"
#include "core/version.hpp"
#include "core/utc_stamp.hpp"
#include "points/point_catalog.hpp"
#include "points/record_controller.hpp"
#include "runtime/mode.hpp"

namespace epa::web {

namespace {

using nlohmann::json;
using P = points::PointId;

// A key that is a point's public name is the catalog's, so the API and the register map agree.
std::string k(P id) { return std::string(points::name(id)); }

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
// Trend values rounded to 1e-4, so a poll of 600 points stays small.
json short_num(double v) { return std::isfinite(v) ? json(std::round(v * 1e4) / 1e4) : json(nullptr); }

json move_json(const runtime::MoveMetricsView& m) {
  return {{"number", m.number}, {"from_mm", num(m.from_mm)}, {"to_mm", num(m.to_mm)}, {"rise_s", num(m.rise_s)},
          {"settling_s", num(m.settling_s)}, {"ess_mm", num(m.ess_mm)}, {"overshoot_pct", num(m.overshoot_pct)},
          {"end", std::string(core::to_string(static_cast<core::MoveEnd>(m.end)))},
          {"controller", std::string(control::to_string(m.controller))}};
}

json poly(const std::array<double, control::kMaxLawOrder + 1>& c, std::size_t n) {
  json a = json::array();
  // n is the degree: n + 1 coefficients.
  for (std::size_t i = 0; i <= n && i < c.size(); ++i) a.push_back(num(c[i]));
  return a;
}

// The status word (points::status_word) packed and bit by bit, each bit by its point's name.
json status_bits(std::uint16_t word) {
  json bits = json::object();
  for (int i = 0; i < runtime::kStatusBits; ++i)
    bits[k(points::indexed_id(P::kStatusBit0, static_cast<std::size_t>(i)))] = (word & (1u << i)) != 0;
  return bits;
}

json health_object(const points::HealthReport& h) {
  const auto& v = h.view;
  const bool drifting = v.effect != points::HealthEffectCode::kNone;
  return {{"state", std::string(points::to_string(v.state))},
          {"effect", std::string(points::to_string(v.effect))},
          {"size", h.size},
          {"ratio", drifting ? num(v.ratio) : json(nullptr)},
          {"value", drifting ? num(v.value) : json(nullptr)},
          {"commissioned", drifting ? num(v.commissioned) : json(nullptr)},
          {"unit", h.unit},
          {"moves_since_onset", v.moves_since_onset},
          {"moves_seen", v.moves_seen},
          {"reason", h.reason}};
}

}  // namespace

std::string health_json(const points::HealthReport& health) {
  json j = health_object(health);
  j["window_gap_mm"] = num(health.window_gap_mm);
  j["baseline_gap_mm"] = num(health.baseline_gap_mm);
  j["moves_dropped"] = health.moves_dropped;
  json trend = json::array();
  for (const auto& judgement : health.trend) {
    json estimates = json::array();
    for (const auto& e : judgement.estimates)
      estimates.push_back({{"effect", std::string(points::to_string(e.effect))}, {"ratio", num(e.ratio)}, {"reduction", num(e.reduction)}});
    trend.push_back({{"move", judgement.move}, {"estimates", std::move(estimates)}});
  }
  j["trend"] = std::move(trend);
  return j.dump();
}

std::string status_json(const runtime::Snapshot& s, const ModbusStats& modbus, bool commands_enabled, const StoreStats& store,
                        const points::HealthReport& health, const std::optional<CertificateLogin>& login) {
  const bool faulted = s.mode == runtime::Mode::kFault;
  const std::uint16_t word = points::status_word(s, store.ok && !store.disk_low, points::health_warns(health.view.state));
  json j = {
      {"version", std::string(core::kVersion)},
      {"cycle", s.cycle},
      {"time_s", num(s.time_s)},
      {"Ts", num(s.Ts)},
      {k(P::kMode), std::string(runtime::to_string(s.mode))},
      {"fault", std::string(runtime::to_string(s.fault))},
      {"fault_text", faulted ? json(std::string(runtime::describe(s.fault))) : json(nullptr)},
      {k(P::kController), std::string(control::to_string(s.controller))},
      {"controller_name", std::string(control::display_name(s.controller))},
      {k(P::kRunningController), std::string(control::to_string(s.running_law))},
      {k(P::kSaturated), s.saturated},
      {k(P::kIoOk), s.io_ok},
      {k(P::kSetpoint), num(s.setpoint_mm)},
      {k(P::kPosition), num(s.position_mm)},
      {k(P::kSensor), num(s.sensor_v)},
      {k(P::kError), num(s.error_mm)},
      {k(P::kValve), num(s.valve_v)},
      {"controller_v", num(s.controller_v)},
      {k(P::kManualValve), num(s.manual_valve_v)},
      {k(P::kHeartbeat), s.heartbeat},
      {k(P::kExciteLeft), num(s.excitation_left_s)},
      {"counters",
       {{k(P::kMoves), s.moves}, {k(P::kFaults), s.faults}, {k(P::kIoErrors), s.io_errors},
        {k(P::kCommandsApplied), s.commands_applied}, {k(P::kCommandsRejected), s.commands_rejected},
        {k(P::kLastCommandRefusal), s.last_refusal == runtime::CommandRefusal::kNone
                                        ? json(nullptr)
                                        : json(std::string(runtime::describe(s.last_refusal)))}}},
      {"last_move", s.last_move.number ? move_json(s.last_move) : json(nullptr)},
      {"loop",
       {{"wake_p50_us", num(s.loop.wake_p50_us)}, {"wake_p99_us", num(s.loop.wake_p99_us)},
        {"wake_max_us", num(s.loop.wake_max_us)}, {"jitter_p50_us", num(s.loop.jitter_p50_us)},
        {"jitter_p99_us", num(s.loop.jitter_p99_us)}, {"jitter_max_us", num(s.loop.jitter_max_us)},
        {"compute_p50_us", num(s.loop.compute_p50_us)}, {"compute_p99_us", num(s.loop.compute_p99_us)},
        {"compute_max_us", num(s.loop.compute_max_us)}, {"cycles", s.loop.cycles}, {"overruns", s.loop.overruns}}},
      {"modbus",
       {{"enabled", modbus.enabled}, {"clients", modbus.clients}, {"requests", modbus.requests},
        {"exceptions", modbus.exceptions}}},
      {"store",
       {{"enabled", store.enabled}, {"ok", store.ok}, {"accepted", store.accepted}, {"saved", store.saved},
        {"last_error", store.last_error.empty() ? json(nullptr) : json(store.last_error)},
        {"tuning_set", store.enabled ? json(store.tuning_set) : json(nullptr)},
        {"disk_low", store.disk_low}}},
      {k(P::kStatusWord), word},
      {"status_bits", status_bits(word)},
      {k(P::kControlWord), s.axis.control_word},
      {"commands_enabled", commands_enabled},
      {"client_certificate", login ? json{{"subject", login->subject}, {"role", login->role}, {"rights", login->rights}} : json(nullptr)},
      {"any_address_may_command", modbus.any_address_may_command},
      {"health", health_object(health)},
  };
  return j.dump();
}

std::string trend_json(const std::vector<TrendPoint>& points, const runtime::Snapshot& s) {
  json t = json::array(), r = json::array(), y = json::array(), u = json::array();
  for (const auto& p : points) {
    t.push_back(short_num(p.t_s));
    r.push_back(short_num(p.setpoint_mm));
    y.push_back(short_num(p.position_mm));
    u.push_back(short_num(p.valve_v));
  }
  json j = {{"period_s", TrendBuffer::kPeriodS}, {"window_s", TrendBuffer::kWindowS},
            {"dead_zone", {{k(P::kBl), num(s.tuning.b_l)}, {k(P::kBr), num(s.tuning.b_r)}}},
            {"valve_limit_v", num(s.tuning.valve_limit_v)},
            {"t_s", std::move(t)}, {k(P::kSetpoint), std::move(r)}, {k(P::kPosition), std::move(y)}, {k(P::kValve), std::move(u)}};
  return j.dump();
}

std::string moves_json(const std::vector<MoveRecord>& moves) {
  json a = json::array();
  for (const auto& m : moves) {
    json e = move_json(m.metrics);  // its controller: the law that ran the move
    e["finished_s"] = num(m.finished_s);
    a.push_back(std::move(e));
  }
  return json{{"moves", std::move(a)}}.dump();
}

std::string tuning_json(const runtime::Snapshot& s) {
  const auto& t = s.tuning;
  json j = {{k(P::kController), std::string(control::to_string(s.controller))},
            {"Ts", num(s.Ts)},
            {k(P::kMr), num(t.m_r)}, {k(P::kMl), num(t.m_l)}, {k(P::kBr), num(t.b_r)}, {k(P::kBl), num(t.b_l)},
            {k(P::kLc), num(t.lc_mm)}, {"valve_limit_v", num(t.valve_limit_v)},
            {k(P::kTrajSpeedFraction), num(t.traj_speed_fraction)}, {k(P::kTrajBandwidth), num(t.traj_bandwidth_rad_s)},
            {k(P::kTrajHoldBand), num(t.traj_hold_band_mm)},
            {"F", poly(t.F, t.nF)}, {"G", poly(t.G, t.nG)}, {"H", poly(t.H, t.nH)}};
  return j.dump();
}

std::string audit_json(const std::vector<core::AuditEntry>& entries) {
  json a = json::array();
  for (auto it = entries.rbegin(); it != entries.rend(); ++it)  // newest first
    a.push_back({{"unix_time_ms", it->unix_time_ms}, {"source", it->source}, {"point", it->point},
                 {"old_value", num(it->old_value)}, {"new_value", num(it->new_value)}});
  return json{{"entries", std::move(a)}}.dump();
}

std::string faults_json(std::uint64_t count, const std::vector<runtime::FaultRecord>& newest_first,
                        std::optional<std::uint64_t> dropped) {
  json a = json::array();
  for (const auto& f : newest_first)
    a.push_back({{"time", core::iso_utc(f.time_ms)}, {"time_ms", f.time_ms}, {"code", static_cast<int>(f.code)},
                 {"name", f.name}, {"text", f.text}, {k(P::kMode), std::string(runtime::to_string(f.mode))},
                 {k(P::kPosition), num(f.position_mm)}, {k(P::kSetpoint), num(f.setpoint_mm)}, {k(P::kValve), num(f.valve_v)},
                 {k(P::kSensor), num(f.sensor_v)}});
  json j = {{"count", count}, {"faults", std::move(a)}};
  if (dropped) j["dropped"] = *dropped;
  return j.dump();
}

std::string points_json(const points::WriteLimits& limits) {
  json a = json::array();
  for (const auto& p : points::point_catalog()) {
    static constexpr const char* kAccess[] = {"r", "rw", "rw after unlock", "key (Modbus only)"};
    json e = {{"name", std::string(p.name)}, {"unit", std::string(p.unit)}, {"access", kAccess[static_cast<int>(p.access)]},
              {"description", std::string(p.description)}};
    if (p.gated()) {
      const auto& r = limits.range(p.id);
      e["min"] = r.min.value;
      e["max"] = r.max.value;
      e["integer"] = p.integer;
    }
    a.push_back(std::move(e));
  }
  return json{{"points", std::move(a)}}.dump();
}

std::string records_json(const points::PositionRecords& records, int record_select) {
  json a = json::array();
  for (std::size_t i = 0; i < records.size(); ++i) {
    const auto& r = records[i];
    using K = RecordKeys;
    a.push_back({{K::kRecord, i + 1}, {K::kTarget, num(r.target_mm)}, {K::kSpeed, num(r.speed_mm_s)},
                 {K::kWindow, num(r.window_mm)}, {K::kController, points::record_controller_name(r.controller)},
                 {K::kApproach, points::record_approach_name(r.approach)}});
  }
  return json{{"records", std::move(a)}, {k(P::kRecordSelect), record_select}}.dump();
}

std::string error_json(const std::string& message) { return json{{"error", message}}.dump(); }

}  // namespace epa::web
