#pragma once
// Units shared by the model, the controller and the tools. The model's output y is in sensor
// volts (0-10 V over the 500 mm stroke), as docs/paper.md reads the paper: a user-facing position is in mm.

#include <algorithm>
#include <cmath>

namespace epa::core {

inline constexpr double kMmPerSensorVolt = 50.0;  // magnetic position sensor: 0-10 V = 0-500 mm
inline constexpr double kStrokeMm = 500.0;        // FESTO cylinder stroke

constexpr double mm_to_sensor_v(double position_mm) { return position_mm / kMmPerSensorVolt; }
constexpr double sensor_v_to_mm(double sensor_v) { return sensor_v * kMmPerSensorVolt; }

// Whether two sample times (s) are the same: a model's, a run's and the loop's period come from
// files and configuration as decimal text, so they agree to a part in 1e9 or differ by a real
// amount. One rule for every place that refuses a model or run of another Ts.
inline bool same_sample_time(double a_s, double b_s) {
  return std::abs(a_s - b_s) <= 1e-9 * std::max(std::abs(a_s), std::abs(b_s));
}

}  // namespace epa::core
