#pragma once
// pp-traj's parameters as a tuning set keeps them: in the user's units (mm, s, rad/s), stored as a
// JSON object in the tuning_sets table and as [trajectory] in tuning files. Keys left out keep
// their defaults (control::TrajectoryConfig's); 0 in accel_mm_s2 and integral_gain_per_mm_s means
// "derived from the model". Unknown keys are refused with their name.
#include <string>
#include <utility>
#include <vector>

#include "control/trajectory_law.hpp"
#include "core/result.hpp"

namespace epa::store {

struct TrajectorySettings {
  double speed_fraction = 0.8;
  double accel_mm_s2 = 0.0;
  double accel_per_distance_per_s2 = 200.0;
  double smoothing_s = 0.05;
  double feedback_bandwidth_rad_s = 4.0;
  double filter_ratio = 4.0;
  double integral_gain_per_mm_s = 0.0;
  double integrator_band_mm = 0.025;
  double hold_band_mm = 0.075;
  double error_filter_s = 0.05;
  double idz_ramp_v = 0.0;
  double creep_margin_v = 0.2;

  bool operator==(const TrajectorySettings&) const = default;
};

// The law's configuration in sensor volts for a model with `mm_per_volt`.
control::TrajectoryConfig to_trajectory_config(const TrajectorySettings& s, double mm_per_volt);

std::string to_json_text(const TrajectorySettings& s);
// Errors name `what`, the key and what was expected (a number; no unknown keys).
core::Result<TrajectorySettings> trajectory_settings_from_json_text(const std::string& text, const std::string& what);

// Every parameter with its key, in a fixed order (files, pages).
std::vector<std::pair<std::string, double>> trajectory_setting_values(const TrajectorySettings& s);

// Sets one parameter by its key (the JSON and TOML key); false for an unknown key.
bool set_trajectory_setting(TrajectorySettings& s, const std::string& key, double value);

}  // namespace epa::store
