#include "store/tuning_set.hpp"

#include <cmath>

#include "core/format.hpp"
#include "store/tuning_points.hpp"

namespace epa::store {

control::ControllerConfig controller_config(const TuningSet& set, const core::HammersteinModel& model, double safe_valve_v) {
  const core::SensorCalibration sensor{model.mm_per_volt};
  control::ControllerConfig law;
  law.kind = set.controller;
  law.F = set.F, law.G = set.G, law.H = set.H;
  law.valve_limit_v = set.valve_limit_v;
  law.safe_valve_v = safe_valve_v;
  law.A = model.A, law.B = model.B, law.Ts = model.Ts;
  law.trajectory = to_trajectory_config(set.trajectory, sensor);
  return points::with_tuning_values(law, tuning_values(set), sensor);  // the dead zone, l_c and the tuning points' own
}

core::Status validate(const TuningSet& set, const core::HammersteinModel& model) {
  auto fail = [&set](const std::string& what) {
    return core::invalid_argument("tuning set '" + set.name + "': " + what);
  };
  if (auto s = model.validate(); !s) return fail("its model: " + s.error().message);
  if (!std::isfinite(set.lc_mm) || set.lc_mm < 0) return fail("lc_mm " + core::format_number(set.lc_mm) + " is not >= 0");
  for (const auto kind : control::kAllControllerKinds) {
    auto config = controller_config(set, model, 0.0);
    config.kind = kind;
    // pp-traj needs an integrating model; a set on another model stays valid for the other laws.
    if (kind == control::ControllerKind::kPpTraj && set.controller != kind) continue;
    if (auto p = control::ControllerParams::make(config); !p) return fail(p.error().message);
  }
  return core::ok();
}

}  // namespace epa::store
