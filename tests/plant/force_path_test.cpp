// A force on the piston moves it through the model's mechanical path: a first-order lag at the
// slowest real pole of A', at the model's steady speed per volt, without B's swing.
#include "plant/force_path.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"
#include "plant/hammerstein_plant.hpp"

namespace {

// Increments of position (mm per sample) of a plant at rest pushed by a constant force.
std::vector<double> increments_under_force(const epa::core::HammersteinModel& model, double force_v, int samples) {
  auto p = epa::plant::HammersteinPlant::make(model, {.initial_position_mm = 100.0, .stroke_mm = 1e6});
  EXPECT_TRUE(p.has_value());
  std::vector<double> inc;
  double last = p->position_mm();
  for (int k = 0; k < samples; ++k) {
    p->step(0.0, force_v);
    inc.push_back(p->position_mm() - last);
    last = p->position_mm();
  }
  return inc;
}

TEST(ForcePath, ThePaperModelsMechanicalPoleIsTheSlowRootOfAPrime) {
  const auto path = epa::plant::force_path(epa::core::paper::model());
  // A' = 1 + 0.0906 q^-1 - 0.5204 q^-2: roots (-0.0906 +- sqrt(0.0906^2 + 4 * 0.5204)) / 2.
  const double p = (-0.0906 + std::sqrt(0.0906 * 0.0906 + 4 * 0.5204)) / 2, p2 = (-0.0906 - std::sqrt(0.0906 * 0.0906 + 4 * 0.5204)) / 2;
  EXPECT_NEAR(path.pole, p, 1e-9);
  EXPECT_EQ(path.nc, 2u);
  EXPECT_NEAR(path.c[2] / path.c[1], -p2, 1e-9);
  EXPECT_NEAR(path.speed_mm_s_per_V, 0.007 / 0.5702 * 50.0 / 0.005, 0.1);
}

TEST(ForcePath, AForceMovesThePistonAsALagToTheSteadySpeedWithoutASwing) {
  const auto model = epa::core::paper::model();
  const auto path = epa::plant::force_path(model);
  const auto inc = increments_under_force(model, 0.5, 60);
  for (std::size_t k = 1; k < inc.size(); ++k) EXPECT_GE(inc[k], inc[k - 1] - 1e-12) << k;  // no Nyquist swing
  const double steady_mm_per_sample = 0.5 * path.speed_mm_s_per_V * model.Ts;
  EXPECT_NEAR(inc.back(), steady_mm_per_sample, 1e-6 * steady_mm_per_sample);
  // A first-order lag: the first increment is (1 - p) of the steady one, each next closes p of the rest.
  EXPECT_NEAR(inc[0], (1.0 - path.pole) * steady_mm_per_sample, 1e-9);
  EXPECT_NEAR(steady_mm_per_sample - inc[1], path.pole * (steady_mm_per_sample - inc[0]), 1e-9);
}

TEST(ForcePath, AModelWithoutARealMechanicalPoleTakesTheForceAtItsSteadySpeed) {
  auto model = epa::core::paper::model();
  // A' = 1 - 0.6 q^-1 + 0.5 q^-2: complex roots. A = (1 - q^-1) A'.
  model.A = {1.0, -1.6, 1.1, -0.5};
  const auto path = epa::plant::force_path(model);
  EXPECT_EQ(path.pole, 0.0);
  const auto inc = increments_under_force(model, 1.0, 300);
  EXPECT_NEAR(inc.back(), path.speed_mm_s_per_V * model.Ts, 1e-6);
}

}  // namespace
