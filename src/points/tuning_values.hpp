#pragma once
// The values the tuning points set, in the units the points show (lengths in mm): the one map from
// a tuning point to its value, which the write gate and the store both edit through, and the one
// place those values enter the law's configuration (lengths in sensor volts there).
#include "control/controller.hpp"
#include "core/sensor_calibration.hpp"
#include "points/point_id.hpp"

namespace epa::points {

struct TuningValues {
  double m_r = 1, m_l = 1, b_r = 0, b_l = 0;  // the dead zone: slopes, break points in V (valve volts)
  double lc_mm = 0;                            // FF-IDZ switch-off band l_c
  double traj_speed_fraction = 0, traj_bandwidth_rad_s = 0, traj_hold_band_mm = 0;  // pp-traj's own
};

// The value tuning point `id` sets; null for any other point (the controller included: a choice of
// law, not a value of one).
double TuningValues::*tuning_value(PointId id);

// `law` with `id`'s value set to `value` (in the point's units); false when `id` sets no value.
bool set_tuning_value(control::ControllerConfig& law, PointId id, double value, core::SensorCalibration sensor);

// `law` with every one of `values` in it.
control::ControllerConfig with_tuning_values(control::ControllerConfig law, const TuningValues& values, core::SensorCalibration sensor);

}  // namespace epa::points
