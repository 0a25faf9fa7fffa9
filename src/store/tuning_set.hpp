#pragma once
// A tuning set: everything the control law needs besides the runtime limits. The controller,
// the RST polynomials (or the design spec that produced them), the dead-zone compensation
// parameters, l_c and the valve limit, and the model it was designed for. One set is active.
#include <cstdint>
#include <string>

#include "control/controller.hpp"
#include "core/hammerstein_model.hpp"
#include "store/trajectory_settings.hpp"

namespace epa::store {

struct TuningSet {
  std::int64_t id = 0;  // 0 until stored
  std::string name;
  std::int64_t created_ms = 0, modified_ms = 0;
  std::string source;  // "seeded from config/: paper eq 12-13", "epa design --poles ...", "imported from x.toml"
  std::int64_t model_id = 0;
  control::ControllerKind controller = control::ControllerKind::kPpFfidz;
  core::Polynomial F, G, H;
  std::string design_json = "{}";  // the design spec (poles, model) that produced F, G, H
  core::DeadZone dead_zone;        // what NG-IDZ and FF-IDZ invert, V
  double lc_mm = 5.0;              // FF-IDZ switch-off band l_c
  double valve_limit_v = 5.0;
  TrajectorySettings trajectory;   // pp-traj's own parameters
};

// The control law's configuration for `set` designed on `model`: the one place a set's lengths
// (l_c, pp-traj's) become the law's sensor volts, through the model's sensor calibration.
control::ControllerConfig controller_config(const TuningSet& set, const core::HammersteinModel& model, double safe_valve_v);

// Validates the set as the loop would use it; the message names the set and what is wrong.
core::Status validate(const TuningSet& set, const core::HammersteinModel& model);

}  // namespace epa::store
