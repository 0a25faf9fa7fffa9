#include "store/tuning_points.hpp"

namespace epa::store {

bool apply_tuning_point(TuningSet& set, std::string_view point, double value) {
  if (point == "m_r") set.dead_zone.m_r = value;
  else if (point == "m_l") set.dead_zone.m_l = value;
  else if (point == "b_r") set.dead_zone.b_r = value;
  else if (point == "b_l") set.dead_zone.b_l = value;
  else if (point == "lc_mm") set.lc_mm = value;
  else if (point == "controller") {
    const int k = static_cast<int>(value);
    if (k < 0 || k >= static_cast<int>(control::kAllControllerKinds.size()) || k != value) return false;
    set.controller = control::kAllControllerKinds[static_cast<std::size_t>(k)];
  } else {
    return false;
  }
  return true;
}

bool is_tuning_point(std::string_view point) {
  TuningSet scratch;
  return apply_tuning_point(scratch, point, 0.0);
}

}  // namespace epa::store
