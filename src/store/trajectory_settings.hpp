#pragma once
// pp-traj's parameters as a tuning set keeps them: in the user's units (mm, s, rad/s), stored as a
// JSON object in the tuning_sets table and as [trajectory] in tuning files. Keys left out keep
// their defaults (control::TrajectoryConfig's); 0 in accel_mm_s2 and integral_gain_per_mm_s means
// "derived from the model". Unknown keys are refused with their name.
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "control/trajectory_law.hpp"
#include "core/result.hpp"
#include "core/sensor_calibration.hpp"
#include "core/units.hpp"

namespace epa::store {

// The law's own defaults, in these units (at the rig's 50 mm per sensor volt): one set of values.
inline constexpr control::TrajectoryConfig kTrajectoryDefaults{};

struct TrajectorySettings {
  double speed_fraction = kTrajectoryDefaults.speed_fraction;
  double accel_mm_s2 = core::sensor_v_to_mm(kTrajectoryDefaults.accel_v_s2);
  double accel_per_distance_per_s2 = kTrajectoryDefaults.accel_per_distance;
  double smoothing_s = kTrajectoryDefaults.smoothing_s;
  double feedback_bandwidth_rad_s = kTrajectoryDefaults.feedback_bandwidth_rad_s;
  double filter_ratio = kTrajectoryDefaults.filter_ratio;
  double integral_gain_per_mm_s = kTrajectoryDefaults.integral_gain_per_s / core::kMmPerSensorVolt;
  double integrator_band_mm = core::sensor_v_to_mm(kTrajectoryDefaults.integrator_band_v);
  double hold_band_mm = core::sensor_v_to_mm(kTrajectoryDefaults.hold_band_v);
  double error_filter_s = kTrajectoryDefaults.error_filter_s;
  double idz_ramp_v = kTrajectoryDefaults.idz_ramp;
  double creep_margin_v = kTrajectoryDefaults.creep_margin_v;
  double creep_blend_s = kTrajectoryDefaults.creep_blend_s;
  // Arrival while sliding on an axis with stick-slip (control/sliding_approach.hpp); coast_s 0: off.
  double coast_s = kTrajectoryDefaults.coast_s;
  double coast_dead_length_mm = core::sensor_v_to_mm(kTrajectoryDefaults.coast_dead_length_v);
  double approach_speed_mm_s = core::sensor_v_to_mm(kTrajectoryDefaults.approach_speed_v_s);
  double approach_mm = core::sensor_v_to_mm(kTrajectoryDefaults.approach_length_v);
  double approach_decel_mm_s2 = core::sensor_v_to_mm(kTrajectoryDefaults.approach_decel_v_s2);
  double retry_band_mm = core::sensor_v_to_mm(kTrajectoryDefaults.retry_band_v);
  double max_retries = kTrajectoryDefaults.max_retries;
  double approach_settle_s = kTrajectoryDefaults.approach_settle_s;

  bool operator==(const TrajectorySettings&) const = default;
};

// The law's configuration in sensor volts for a model whose sensor reads `sensor`.
control::TrajectoryConfig to_trajectory_config(const TrajectorySettings& s, core::SensorCalibration sensor);

std::string to_json_text(const TrajectorySettings& s);
// Errors name `what`, the key and what was expected (a number; no unknown keys).
core::Result<TrajectorySettings> trajectory_settings_from_json_text(const std::string& text, const std::string& what);

// Every parameter with its key, in a fixed order (files, pages).
std::vector<std::pair<std::string, double>> trajectory_setting_values(const TrajectorySettings& s);
// The keys alone, in the same order (what an unknown key's message lists).
std::vector<std::string_view> trajectory_setting_keys();

// Sets one parameter by its key (the JSON and TOML key); false for an unknown key.
bool set_trajectory_setting(TrajectorySettings& s, const std::string& key, double value);

}  // namespace epa::store
