#include "store/tuning_points.hpp"

namespace epa::store {

bool apply_tuning_point(TuningSet& set, points::PointId point, double value) {
  using P = points::PointId;
  switch (point) {
    case P::kMr: set.dead_zone.m_r = value; return true;
    case P::kMl: set.dead_zone.m_l = value; return true;
    case P::kBr: set.dead_zone.b_r = value; return true;
    case P::kBl: set.dead_zone.b_l = value; return true;
    case P::kLc: set.lc_mm = value; return true;
    case P::kTrajSpeedFraction: set.trajectory.speed_fraction = value; return true;
    case P::kTrajBandwidth: set.trajectory.feedback_bandwidth_rad_s = value; return true;
    case P::kTrajHoldBand: set.trajectory.hold_band_mm = value; return true;
    case P::kController: {
      const int k = static_cast<int>(value);
      if (k < 0 || k >= static_cast<int>(control::kAllControllerKinds.size()) || k != value) return false;
      set.controller = control::kAllControllerKinds[static_cast<std::size_t>(k)];
      return true;
    }
    default: return false;
  }
}

}  // namespace epa::store
