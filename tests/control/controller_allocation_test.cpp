// Proves the control law allocates nothing: operator new is replaced for this whole test process
// and counted while the loop runs (ARCHITECTURE.md: the cycle never allocates).
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

TEST(Allocation, TenThousandControllerStepsAllocateNothing) {
  for (ControllerKind kind : kAllControllerKinds) {
    auto params = ControllerParams::make(paper_controller_config(kind));
    ASSERT_TRUE(params.has_value());
    auto plant = plant::HammersteinPlant::make(core::paper::model(), {.noise_std_mm = 0.1});
    ASSERT_TRUE(plant.has_value());
    ControllerState state;
    double sink = 0.0;
    const long before = epa::testing::allocation_count();
    for (int k = 0; k < 10000; ++k) {
      const double r_v = (k / 2000) % 2 == 0 ? 1.0 : 3.0;  // setpoint changes keep all branches busy
      const auto out = controller_step(*params, state, r_v, plant->measured_v());
      plant->step(out.valve_v);
      sink += out.valve_v;
    }
    EXPECT_EQ(epa::testing::allocation_count() - before, 0) << to_string(kind);
    EXPECT_TRUE(std::isfinite(sink));
  }
}

TEST(Allocation, PpTrajArrivingWhileSlidingAllocatesNothing) {
  auto config = paper_controller_config(ControllerKind::kPpTraj);
  config.trajectory.coast_s = 0.025;  // the sliding arrival (sliding_approach.hpp): legs, cuts, retries
  auto params = ControllerParams::make(config);
  ASSERT_TRUE(params.has_value());
  auto plant = plant::HammersteinPlant::make(core::paper::model(), {.noise_std_mm = 0.1});
  ASSERT_TRUE(plant.has_value());
  ControllerState state;
  double sink = 0.0;
  const long before = epa::testing::allocation_count();
  for (int k = 0; k < 10000; ++k) {
    const double r_v = (k / 2000) % 2 == 0 ? 4.0 : 4.5;  // short moves too: back-offs
    const auto out = controller_step(*params, state, r_v, plant->measured_v());
    plant->step(out.valve_v);
    sink += out.valve_v;
  }
  EXPECT_EQ(epa::testing::allocation_count() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace epa::control
