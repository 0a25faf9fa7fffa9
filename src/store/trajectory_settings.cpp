#include "store/trajectory_settings.hpp"

#include <array>
#include <nlohmann/json.hpp>
#include <utility>

namespace epa::store {

namespace {

// One table of keys, so the JSON writer, the reader and the points agree.
using Member = double TrajectorySettings::*;
constexpr std::array<std::pair<const char*, Member>, 21> kKeys = {{
    {"speed_fraction", &TrajectorySettings::speed_fraction},
    {"accel_mm_s2", &TrajectorySettings::accel_mm_s2},
    {"accel_per_distance_per_s2", &TrajectorySettings::accel_per_distance_per_s2},
    {"smoothing_s", &TrajectorySettings::smoothing_s},
    {"feedback_bandwidth_rad_s", &TrajectorySettings::feedback_bandwidth_rad_s},
    {"filter_ratio", &TrajectorySettings::filter_ratio},
    {"integral_gain_per_mm_s", &TrajectorySettings::integral_gain_per_mm_s},
    {"integrator_band_mm", &TrajectorySettings::integrator_band_mm},
    {"hold_band_mm", &TrajectorySettings::hold_band_mm},
    {"error_filter_s", &TrajectorySettings::error_filter_s},
    {"idz_ramp_v", &TrajectorySettings::idz_ramp_v},
    {"creep_margin_v", &TrajectorySettings::creep_margin_v},
    {"creep_blend_s", &TrajectorySettings::creep_blend_s},
    {"coast_s", &TrajectorySettings::coast_s},
    {"coast_dead_length_mm", &TrajectorySettings::coast_dead_length_mm},
    {"approach_speed_mm_s", &TrajectorySettings::approach_speed_mm_s},
    {"approach_mm", &TrajectorySettings::approach_mm},
    {"approach_decel_mm_s2", &TrajectorySettings::approach_decel_mm_s2},
    {"retry_band_mm", &TrajectorySettings::retry_band_mm},
    {"max_retries", &TrajectorySettings::max_retries},
    {"approach_settle_s", &TrajectorySettings::approach_settle_s},
}};

}  // namespace

control::TrajectoryConfig to_trajectory_config(const TrajectorySettings& s, core::SensorCalibration sensor) {
  control::TrajectoryConfig c;
  c.speed_fraction = s.speed_fraction;
  c.accel_v_s2 = sensor.to_volts(s.accel_mm_s2);
  c.accel_per_distance = s.accel_per_distance_per_s2;
  c.smoothing_s = s.smoothing_s;
  c.feedback_bandwidth_rad_s = s.feedback_bandwidth_rad_s;
  c.filter_ratio = s.filter_ratio;
  c.integral_gain_per_s = s.integral_gain_per_mm_s * sensor.mm_per_volt;  // u per (mm s) -> u per (V s)
  c.integrator_band_v = sensor.to_volts(s.integrator_band_mm);
  c.hold_band_v = sensor.to_volts(s.hold_band_mm);
  c.error_filter_s = s.error_filter_s;
  c.idz_ramp = s.idz_ramp_v;
  c.creep_margin_v = s.creep_margin_v;
  c.creep_blend_s = s.creep_blend_s;
  c.coast_s = s.coast_s;
  c.coast_dead_length_v = sensor.to_volts(s.coast_dead_length_mm);
  c.approach_speed_v_s = sensor.to_volts(s.approach_speed_mm_s);
  c.approach_length_v = sensor.to_volts(s.approach_mm);
  c.approach_decel_v_s2 = sensor.to_volts(s.approach_decel_mm_s2);
  c.retry_band_v = sensor.to_volts(s.retry_band_mm);
  c.max_retries = s.max_retries;
  c.approach_settle_s = s.approach_settle_s;
  return c;
}

std::vector<std::string_view> trajectory_setting_keys() {
  std::vector<std::string_view> out;
  for (const auto& [key, member] : kKeys) out.emplace_back(key);
  return out;
}

std::vector<std::pair<std::string, double>> trajectory_setting_values(const TrajectorySettings& s) {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& [key, member] : kKeys) out.emplace_back(key, s.*member);
  return out;
}

std::string to_json_text(const TrajectorySettings& s) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [key, member] : kKeys) j[key] = s.*member;
  return j.dump();
}

core::Result<TrajectorySettings> trajectory_settings_from_json_text(const std::string& text, const std::string& what) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return core::parse_error(what + " is not a JSON object: " + text);
  TrajectorySettings s;
  for (const auto& [key, value] : j.items()) {
    if (!value.is_number()) return core::parse_error(what + ": '" + key + "' is not a number");
    if (!set_trajectory_setting(s, key, value.get<double>())) return core::parse_error(what + ": unknown key '" + key + "'");
  }
  return s;
}

bool set_trajectory_setting(TrajectorySettings& s, const std::string& key, double value) {
  for (const auto& [name, member] : kKeys)
    if (key == name) {
      s.*member = value;
      return true;
    }
  return false;
}

}  // namespace epa::store
