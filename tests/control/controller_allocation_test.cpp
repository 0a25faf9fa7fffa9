// Proves the control law allocates nothing: operator new is replaced for this whole test process
// and counted while the loop runs (the cycle never allocates: docs/dev/decisions.md).
#include <gtest/gtest.h>

#include <cmath>

#include "../support/counting_new.hpp"
#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "plant/hammerstein_plant.hpp"

namespace epa::control {
namespace {

TEST(Allocation, CounterSeesAnAllocation) {  // guards against a counter that cannot count
  const long before = epa::testing::allocation_count();
  auto* p = new int(3);
  EXPECT_GT(epa::testing::allocation_count(), before);
  delete p;
}

// Allocations during 10,000 steps of the law on the printed model with sensor noise, the setpoint
// switching between r1_v and r2_v every 2,000 (so that every branch of the law runs).
long allocations_in_10000_steps(const ControllerParams& params, double r1_v, double r2_v) {
  auto plant = plant::HammersteinPlant::make(core::paper::model(), {.noise_std_mm = 0.1});
  EXPECT_TRUE(plant.has_value());
  ControllerState state;
  double sink = 0.0;
  const long before = epa::testing::allocation_count();
  for (int k = 0; k < 10000; ++k) {
    const double r_v = (k / 2000) % 2 == 0 ? r1_v : r2_v;
    const auto out = controller_step(params, state, r_v, plant->measured_v());
    plant->step(out.valve_v);
    sink += out.valve_v;
  }
  const long allocations = epa::testing::allocation_count() - before;
  EXPECT_TRUE(std::isfinite(sink));
  return allocations;
}

TEST(Allocation, TenThousandControllerStepsAllocateNothing) {
  for (ControllerKind kind : kAllControllerKinds) {
    auto params = ControllerParams::make(paper_controller_config(kind));
    ASSERT_TRUE(params.has_value());
    EXPECT_EQ(allocations_in_10000_steps(*params, 1.0, 3.0), 0) << to_string(kind);
  }
}

TEST(Allocation, PpTrajArrivingWhileSlidingAllocatesNothing) {
  auto config = paper_controller_config(ControllerKind::kPpTraj);
  config.trajectory.coast_s = 0.025;  // the sliding arrival (sliding_approach.hpp): legs, cuts, retries
  auto params = ControllerParams::make(config);
  ASSERT_TRUE(params.has_value());
  EXPECT_EQ(allocations_in_10000_steps(*params, 4.0, 4.5), 0);  // short moves too: back-offs
}

}  // namespace
}  // namespace epa::control
