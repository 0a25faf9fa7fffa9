#include "store/tuning_set.hpp"

#include <cmath>

#include "core/format.hpp"

namespace epa::store {

control::ControllerConfig controller_config(const TuningSet& set, const core::HammersteinModel& model, double safe_valve_v) {
  return {.kind = set.controller, .F = set.F, .G = set.G, .H = set.H, .dead_zone = set.dead_zone,
          .lc_v = set.lc_mm / model.mm_per_volt, .valve_limit_v = set.valve_limit_v, .safe_valve_v = safe_valve_v,
          .A = model.A, .B = model.B, .Ts = model.Ts,
          .trajectory = to_trajectory_config(set.trajectory, model.mm_per_volt)};
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
