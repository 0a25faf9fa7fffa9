#include "commission/commission_spec.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "core/format.hpp"
#include "core/strict_json.hpp"

namespace epa::commission {

namespace {

core::Status in_range(const char* key, double v, double lo, double hi, bool lo_open = false) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (ok) return core::ok();
  return core::invalid_argument(std::string("commission spec: ") + key + " " + core::format_number(v) + " is outside " +
                                (lo_open ? "(" : "[") + core::format_number(lo) + ", " + core::format_number(hi) + "]");
}

// A number from `j[key]` into `out`, or the error naming the key.
core::Status read_number(const nlohmann::json& j, const char* key, double& out, const char* parent = "") {
  if (!j.contains(key)) return core::ok();
  if (!j[key].is_number()) return core::invalid_argument(std::string("commission spec: ") + parent + key + " must be a number");
  out = j[key].get<double>();
  return core::ok();
}

// One table of a verification move's limits, so the reader, the writer and the range checks agree.
struct LimitKey {
  const char* name;
  double MoveLimits::*member;
  double hi;
  bool lo_open;  // (0, hi] rather than [0, hi]
};
constexpr std::array<LimitKey, 4> kLimitKeys = {{
    {"ess_mm", &MoveLimits::ess_mm, 100.0, true},
    {"overshoot_pct", &MoveLimits::overshoot_pct, 1000.0, false},
    {"overshoot_mm", &MoveLimits::overshoot_mm, 100.0, false},
    {"settling_s", &MoveLimits::settling_s, 60.0, false},
}};

nlohmann::json limits_json(const MoveLimits& l) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& k : kLimitKeys) j[k.name] = l.*k.member;
  return j;
}

core::Status limits_in_range(const char* parent, const MoveLimits& l) {
  for (const auto& k : kLimitKeys)
    if (auto s = in_range((std::string(parent) + "." + k.name).c_str(), l.*k.member, 0.0, k.hi, k.lo_open); !s) return s;
  return core::ok();
}

}  // namespace

core::Status CommissionSpec::validate(double lo_mm, double hi_mm) const {
  if (excitation_runs < 2 || excitation_runs > 10)
    return core::invalid_argument("commission spec: excitation_runs " + std::to_string(excitation_runs) +
                                  " is outside [2, 10] (one run is held out for validation)");
  for (auto s : {in_range("excitation_s", excitation_s, 5.0, 600.0), in_range("amplitude_max_v", amplitude_max_v, 0.5, 10.0),
                 in_range("overshoot_pct", overshoot_pct, 0.0, 50.0), in_range("settling_s", settling_s, 0.05, 30.0, true),
                 in_range("observer_pole", observer_pole, 0.0, 0.95), in_range("move_hold_s", move_hold_s, 3.0, 60.0),
                 limits_in_range("limits", limits), limits_in_range("robust_limits", robust_limits),
                 in_range("robust_gain", robust_gain, 0.0, 0.9), in_range("robust_breakpoint_v", robust_breakpoint_v, 0.0, 2.0)})
    if (!s) return s;
  if (moves_mm.empty() || moves_mm.size() > 32)
    return core::invalid_argument("commission spec: moves_mm needs 1 to 32 targets, got " + std::to_string(moves_mm.size()));
  for (double m : moves_mm)
    if (auto s = in_range("moves_mm", m, lo_mm, hi_mm); !s) return s;
  if (name.size() > 64) return core::invalid_argument("commission spec: name is longer than 64 characters");
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.'))
      return core::invalid_argument("commission spec: name '" + name + "' may hold only letters, digits, '-', '_' and '.'");
  return core::ok();
}

core::Status check_runnable(const CommissionSpec& spec, const ApplianceBounds& b) {
  if (auto s = spec.validate(b.setpoint_min_mm, b.setpoint_max_mm); !s) return s;
  if (spec.excitation_s > b.excitation_max_s)
    return core::invalid_argument("commission spec: excitation_s " + core::format_number(spec.excitation_s) +
                                  " s does not fit this appliance's recorder: at most " + core::format_number(b.excitation_max_s) +
                                  " s (" + b.excitation_max_source + ")");
  if (spec.amplitude_max_v > b.amplitude_max_v)
    return core::invalid_argument("commission spec: amplitude_max_v " + core::format_number(spec.amplitude_max_v) +
                                  " V is above this appliance's excite_amplitude_max_v limit of " + core::format_number(b.amplitude_max_v) + " V");
  return core::ok();
}

core::Result<CommissionSpec> parse_commission_spec(const std::string& text) {
  // Strict (core/strict_json.hpp): valid UTF-8, each key once, bounded depth; the library's own
  // text, which can quote the invalid bytes, never reaches an answer.
  auto parsed = core::parse_strict_json(text, "commission spec");
  if (!parsed) return parsed.error();
  const nlohmann::json& j = *parsed;
  if (!j.is_object()) return core::parse_error("commission spec: a JSON object is expected, not " + std::string(j.type_name()));
  static const std::set<std::string> known = {"excitation_runs", "excitation_s", "seed", "amplitude_max_v", "controller",
                                              "overshoot_pct", "settling_s", "observer_pole", "moves_mm", "move_hold_s",
                                              "limits", "robust_gain", "robust_breakpoint_v", "robust_limits", "name"};
  for (const auto& [key, value] : j.items())
    if (!known.contains(key)) return core::invalid_argument("commission spec: unknown key '" + key + "'");
  CommissionSpec s;
  if (j.contains("excitation_runs")) {
    if (!j["excitation_runs"].is_number_integer()) return core::invalid_argument("commission spec: excitation_runs must be a whole number");
    s.excitation_runs = j["excitation_runs"].get<int>();
  }
  if (j.contains("seed")) {
    if (!j["seed"].is_number_unsigned()) return core::invalid_argument("commission spec: seed must be a whole number >= 0");
    s.seed = j["seed"].get<std::uint64_t>();
  }
  if (j.contains("controller")) {
    if (!j["controller"].is_string()) return core::invalid_argument("commission spec: controller must be a name");
    auto k = control::parse_controller_kind(j["controller"].get<std::string>());
    if (!k) return core::invalid_argument("commission spec: controller: " + k.error().message);
    s.controller = *k;
  }
  if (j.contains("moves_mm")) {
    if (!j["moves_mm"].is_array()) return core::invalid_argument("commission spec: moves_mm must be a list of targets in mm");
    s.moves_mm.clear();
    for (const auto& m : j["moves_mm"]) {
      if (!m.is_number()) return core::invalid_argument("commission spec: moves_mm must be a list of numbers");
      s.moves_mm.push_back(m.get<double>());
    }
  }
  if (j.contains("name")) {
    if (!j["name"].is_string()) return core::invalid_argument("commission spec: name must be a string");
    s.name = j["name"].get<std::string>();
  }
  for (auto [key, limits] : {std::pair<const char*, MoveLimits*>{"limits", &s.limits}, {"robust_limits", &s.robust_limits}}) {
    if (!j.contains(key)) continue;
    const auto& l = j[key];
    const std::string parent = std::string(key) + ".";
    if (!l.is_object()) return core::invalid_argument(std::string("commission spec: ") + key + " must be an object");
    for (const auto& item : l.items()) {
      const std::string& given = item.key();  // a named variable, not a structured binding: clang 14 (the fuzz build) cannot capture one
      if (std::none_of(kLimitKeys.begin(), kLimitKeys.end(), [&](const LimitKey& limit) { return given == limit.name; }))
        return core::invalid_argument("commission spec: unknown key '" + parent + given + "'");
    }
    for (const auto& k : kLimitKeys)
      if (auto st = read_number(l, k.name, limits->*k.member, parent.c_str()); !st) return st.error();
  }
  for (auto st : {read_number(j, "excitation_s", s.excitation_s), read_number(j, "amplitude_max_v", s.amplitude_max_v),
                  read_number(j, "overshoot_pct", s.overshoot_pct), read_number(j, "settling_s", s.settling_s),
                  read_number(j, "observer_pole", s.observer_pole), read_number(j, "move_hold_s", s.move_hold_s),
                  read_number(j, "robust_gain", s.robust_gain), read_number(j, "robust_breakpoint_v", s.robust_breakpoint_v)})
    if (!st) return st.error();
  if (auto st = s.validate(); !st) return st.error();
  return s;
}

std::string format_commission_spec(const CommissionSpec& s) {
  const nlohmann::json j = {{"excitation_runs", s.excitation_runs},
                            {"excitation_s", s.excitation_s},
                            {"seed", s.seed},
                            {"amplitude_max_v", s.amplitude_max_v},
                            {"controller", std::string(control::to_string(s.controller))},
                            {"overshoot_pct", s.overshoot_pct},
                            {"settling_s", s.settling_s},
                            {"observer_pole", s.observer_pole},
                            {"moves_mm", s.moves_mm},
                            {"move_hold_s", s.move_hold_s},
                            {"limits", limits_json(s.limits)},
                            {"robust_gain", s.robust_gain},
                            {"robust_breakpoint_v", s.robust_breakpoint_v},
                            {"robust_limits", limits_json(s.robust_limits)},
                            {"name", s.name}};
  return j.dump();
}

}  // namespace epa::commission
