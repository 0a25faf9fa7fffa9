#pragma once
// pp-traj designed on a model file as the appliance deploys it: the file's ARX model and dead zone,
// and the sliding arrival's coast from its stick-slip model when the file says that model describes
// the axis (plant::sliding_arrival_coast_s; 0 otherwise: the integrator arrives).
#include <gtest/gtest.h>

#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/model_file.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::testing {

inline control::ControllerConfig pp_traj_config_on(const core::ModelFile& f) {
  auto c = control::paper_controller_config(control::ControllerKind::kPpTraj);
  c.A = f.model.A;
  c.B = f.model.B;
  c.dead_zone = f.model.dead_zone;
  const auto coast = plant::sliding_arrival_coast_s(f, f.model.mm_per_volt * c.trajectory.approach_speed_v_s);
  EXPECT_TRUE(coast.has_value()) << (coast ? "" : coast.error().message);
  c.trajectory.coast_s = coast ? *coast : 0.0;
  return c;
}

}  // namespace epa::testing
