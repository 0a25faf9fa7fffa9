#pragma once
// The physics plant's coast as pp-traj's sliding arrival reads it (control/sliding_approach.hpp):
// driven at valve_v while keep_driving(sample, position_mm) holds, then centred; the speed at the
// cut is the least-squares slope of the last 4 positions, the coast the distance the piston goes
// on in the next 200 samples over that speed. A measurement on a plant of another form than the
// law's model, for the tests that check the coast the law assumes.
#include <array>

#include "core/reading_slope.hpp"
#include "plant/pneumatic_plant.hpp"

namespace epa::testing {

struct PhysicsCoast {
  double speed_mm_s = 0.0;  // at the cut, along `direction`
  double coast_s = 0.0;
};

template <class KeepDriving>
PhysicsCoast measure_physics_coast(plant::PneumaticPlant& physics, double valve_v, double direction, KeepDriving keep_driving) {
  constexpr double kTs = 0.005;
  std::array<double, 4> y{};  // newest first
  y.fill(physics.position_mm());
  for (int k = 0; keep_driving(k, physics.position_mm()); ++k) {
    physics.step(valve_v);
    y = {physics.position_mm(), y[0], y[1], y[2]};
  }
  PhysicsCoast c;
  c.speed_mm_s = direction * core::slope_of_last_four(y, kTs);
  for (int k = 0; k < 200; ++k) physics.step(0.0);
  c.coast_s = direction * (physics.position_mm() - y[0]) / c.speed_mm_s;
  return c;
}

}  // namespace epa::testing
