#include "store/tuning_points.hpp"

namespace epa::store {

points::TuningValues tuning_values(const TuningSet& set) {
  return {.m_r = set.dead_zone.m_r, .m_l = set.dead_zone.m_l, .b_r = set.dead_zone.b_r, .b_l = set.dead_zone.b_l,
          .lc_mm = set.lc_mm, .traj_speed_fraction = set.trajectory.speed_fraction,
          .traj_bandwidth_rad_s = set.trajectory.feedback_bandwidth_rad_s, .traj_hold_band_mm = set.trajectory.hold_band_mm};
}

void set_tuning_values(TuningSet& set, const points::TuningValues& v) {
  set.dead_zone.m_r = v.m_r, set.dead_zone.m_l = v.m_l, set.dead_zone.b_r = v.b_r, set.dead_zone.b_l = v.b_l;
  set.lc_mm = v.lc_mm;
  set.trajectory.speed_fraction = v.traj_speed_fraction;
  set.trajectory.feedback_bandwidth_rad_s = v.traj_bandwidth_rad_s;
  set.trajectory.hold_band_mm = v.traj_hold_band_mm;
}

namespace {

bool set_controller(TuningSet& set, double value) {
  const int k = static_cast<int>(value);
  if (k < 0 || k >= static_cast<int>(control::kAllControllerKinds.size()) || k != value) return false;
  set.controller = control::kAllControllerKinds[static_cast<std::size_t>(k)];
  return true;
}

}  // namespace

bool apply_tuning_point(TuningSet& set, points::PointId point, double value) {
  if (point == points::PointId::kController) return set_controller(set, value);
  const auto field = points::tuning_value(point);
  if (!field) return false;
  points::TuningValues values = tuning_values(set);
  values.*field = value;
  set_tuning_values(set, values);
  return true;
}

}  // namespace epa::store
