#include "web/json_api.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "control/controller_kind.hpp"
#include "runtime/mode.hpp"

namespace epa::web {

namespace {

using nlohmann::json;

json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
// Trend values rounded to 1e-4, so a poll of 600 points stays small.
json short_num(double v) { return std::isfinite(v) ? json(std::round(v * 1e4) / 1e4) : json(nullptr); }

json move_json(const runtime::MoveMetricsView& m) {
  return {{"number", m.number}, {"from_mm", num(m.from_mm)}, {"to_mm", num(m.to_mm)}, {"rise_s", num(m.rise_s)},
          {"settling_s", num(m.settling_s)}, {"ess_mm", num(m.ess_mm)}, {"overshoot_pct", num(m.overshoot_pct)}};
}

json poly(const std::array<double, control::kMaxLawOrder + 1>& c, std::size_t n) {
  json a = json::array();
  // n is the degree: n + 1 coefficients.
  for (std::size_t i = 0; i <= n && i < c.size(); ++i) a.push_back(num(c[i]));
  return a;
}

}  // namespace

std::string status_json(const runtime::Snapshot& s, const ModbusStats& modbus, bool commands_enabled, const StoreStats& store) {
  const bool faulted = s.mode == runtime::Mode::kFault;
  json j = {
      {"cycle", s.cycle},
      {"time_s", num(s.time_s)},
      {"Ts", num(s.Ts)},
      {"mode", std::string(runtime::to_string(s.mode))},
      {"fault", std::string(runtime::to_string(s.fault))},
      {"fault_text", faulted ? json(std::string(runtime::describe(s.fault))) : json(nullptr)},
      {"controller", std::string(control::to_string(s.controller))},
      {"controller_name", std::string(control::display_name(s.controller))},
      {"saturated", s.saturated},
      {"io_ok", s.io_ok},
      {"setpoint_mm", num(s.setpoint_mm)},
      {"position_mm", num(s.position_mm)},
      {"sensor_v", num(s.sensor_v)},
      {"error_mm", num(s.error_mm)},
      {"valve_v", num(s.valve_v)},
      {"controller_v", num(s.controller_v)},
      {"manual_valve_v", num(s.manual_valve_v)},
      {"heartbeat", s.heartbeat},
      {"counters",
       {{"moves", s.moves}, {"faults", s.faults}, {"io_errors", s.io_errors}, {"commands_applied", s.commands_applied},
        {"commands_rejected", s.commands_rejected}}},
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
        {"tuning_set", store.enabled ? json(store.tuning_set) : json(nullptr)}}},
      {"commands_enabled", commands_enabled},
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
            {"dead_zone", {{"b_l", num(s.tuning.b_l)}, {"b_r", num(s.tuning.b_r)}}},
            {"valve_limit_v", num(s.tuning.valve_limit_v)},
            {"t_s", std::move(t)}, {"setpoint_mm", std::move(r)}, {"position_mm", std::move(y)}, {"valve_v", std::move(u)}};
  return j.dump();
}

std::string moves_json(const std::vector<MoveRecord>& moves) {
  json a = json::array();
  for (const auto& m : moves) {
    json e = move_json(m.metrics);
    e["controller"] = std::string(control::to_string(m.controller));
    e["finished_s"] = num(m.finished_s);
    a.push_back(std::move(e));
  }
  return json{{"moves", std::move(a)}}.dump();
}

std::string tuning_json(const runtime::Snapshot& s) {
  const auto& t = s.tuning;
  json j = {{"controller", std::string(control::to_string(s.controller))},
            {"Ts", num(s.Ts)},
            {"m_r", num(t.m_r)}, {"m_l", num(t.m_l)}, {"b_r", num(t.b_r)}, {"b_l", num(t.b_l)},
            {"lc_mm", num(t.lc_mm)}, {"valve_limit_v", num(t.valve_limit_v)},
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

std::string error_json(const std::string& message) { return json{{"error", message}}.dump(); }

}  // namespace epa::web
