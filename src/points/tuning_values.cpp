#include "points/tuning_values.hpp"

#include <array>

namespace epa::points {

namespace {

// Each tuning value: its point, where TuningValues keeps it, where the law keeps it, and whether it
// is a length (mm at the point, sensor volts in the law).
struct TuningValueDef {
  PointId id;
  double TuningValues::*value;
  double& (*in_law)(control::ControllerConfig&);
  bool length;
};

using Law = control::ControllerConfig;
constexpr std::array<TuningValueDef, 8> kTuningValues = {{
    {PointId::kMr, &TuningValues::m_r, [](Law& c) -> double& { return c.dead_zone.m_r; }, false},
    {PointId::kMl, &TuningValues::m_l, [](Law& c) -> double& { return c.dead_zone.m_l; }, false},
    {PointId::kBr, &TuningValues::b_r, [](Law& c) -> double& { return c.dead_zone.b_r; }, false},
    {PointId::kBl, &TuningValues::b_l, [](Law& c) -> double& { return c.dead_zone.b_l; }, false},
    {PointId::kLc, &TuningValues::lc_mm, [](Law& c) -> double& { return c.lc_v; }, true},
    {PointId::kTrajSpeedFraction, &TuningValues::traj_speed_fraction, [](Law& c) -> double& { return c.trajectory.speed_fraction; }, false},
    {PointId::kTrajBandwidth, &TuningValues::traj_bandwidth_rad_s,
     [](Law& c) -> double& { return c.trajectory.feedback_bandwidth_rad_s; }, false},
    {PointId::kTrajHoldBand, &TuningValues::traj_hold_band_mm, [](Law& c) -> double& { return c.trajectory.hold_band_v; }, true},
}};

const TuningValueDef* tuning_value_def(PointId id) {
  for (const auto& d : kTuningValues)
    if (d.id == id) return &d;
  return nullptr;
}

void set_in_law(Law& law, const TuningValueDef& d, double value, core::SensorCalibration sensor) {
  d.in_law(law) = d.length ? sensor.to_volts(value) : value;
}

}  // namespace

double TuningValues::*tuning_value(PointId id) {
  const TuningValueDef* d = tuning_value_def(id);
  return d ? d->value : nullptr;
}

bool set_tuning_value(control::ControllerConfig& law, PointId id, double value, core::SensorCalibration sensor) {
  const TuningValueDef* d = tuning_value_def(id);
  if (d) set_in_law(law, *d, value, sensor);
  return d != nullptr;
}

control::ControllerConfig with_tuning_values(control::ControllerConfig law, const TuningValues& values, core::SensorCalibration sensor) {
  for (const auto& d : kTuningValues) set_in_law(law, d, values.*d.value, sensor);
  return law;
}

}  // namespace epa::points
