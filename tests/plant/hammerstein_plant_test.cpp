#include "plant/hammerstein_plant.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"

namespace epa::plant {
namespace {

constexpr double kTol = 1e-12;

HammersteinPlant paper_plant(PlantOptions o = {}) {
  auto p = HammersteinPlant::make(core::paper::model(), o);
  EXPECT_TRUE(p.has_value());
  return *p;
}

TEST(HammersteinPlant, RestsInsideTheDeadBand) {
  auto p = paper_plant({.initial_position_mm = 100.0});
  for (int k = 0; k < 1000; ++k) p.step(1.2);  // just below b_r = 1.232
  EXPECT_NEAR(p.position_mm(), 100.0, kTol);
}

// y(k+1) = 0.9094 y(k) + 0.6110 y(k-1) - 0.5204 y(k-2) + 1.024 ud(k) - 2.046 ud(k-1) + 1.029 ud(k-2)
TEST(HammersteinPlant, FirstSamplesFollowEq9ByHand) {
  auto p = paper_plant({.initial_position_mm = 100.0});  // y = 2 V at rest
  const double ud = 1.7627 * (2.0 - 1.232);
  p.step(2.0);
  const double y1 = 0.9094 * 2 + 0.6110 * 2 - 0.5204 * 2 + 1.024 * ud;
  EXPECT_NEAR(p.position_v(), y1, kTol);
  p.step(2.0);
  const double y2 = 0.9094 * y1 + 0.6110 * 2 - 0.5204 * 2 + 1.024 * ud - 2.046 * ud;
  EXPECT_NEAR(p.position_v(), y2, kTol);
}

// The plant integrates: a constant u_d gives a constant velocity of B(1)/A'(1) per sample,
// where A = (1 - q) A'(q) and A'(1) = 1 + 0.0906 - 0.5204 = 0.5702.
TEST(HammersteinPlant, ConstantCommandGivesTheIntegratorVelocity) {
  auto p = paper_plant({.initial_position_mm = 100.0});
  const double ud = 1.7627 * (3.0 - 1.232);
  for (int k = 0; k < 200; ++k) p.step(3.0);
  const double before = p.position_v();
  p.step(3.0);
  EXPECT_NEAR(p.position_v() - before, ud * 0.007 / 0.5702, 1e-6);
}

TEST(HammersteinPlant, EndStopsHoldThePistonInsideTheStroke) {
  auto p = paper_plant({.initial_position_mm = 480.0});
  for (int k = 0; k < 2000; ++k) p.step(5.0);
  EXPECT_DOUBLE_EQ(p.position_mm(), 500.0);
  for (int k = 0; k < 4000; ++k) p.step(-5.0);
  EXPECT_DOUBLE_EQ(p.position_mm(), 0.0);
  p.step(0.0);  // no wind-up behind the stop: a centred valve does not push it further
  EXPECT_GE(p.position_mm(), 0.0);
}

TEST(HammersteinPlant, SeededNoiseIsReproducibleAndHasTheRequestedSpread) {
  auto a = paper_plant({.initial_position_mm = 250.0, .noise_std_mm = 0.1, .seed = 42});
  auto b = paper_plant({.initial_position_mm = 250.0, .noise_std_mm = 0.1, .seed = 42});
  double sum = 0, sum2 = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    ASSERT_EQ(a.measured_mm(), b.measured_mm());
    const double e = a.measured_mm() - a.position_mm();
    sum += e;
    sum2 += e * e;
    a.step(0.0);
    b.step(0.0);
  }
  EXPECT_NEAR(sum / n, 0.0, 0.005);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.1, 0.005);
  EXPECT_DOUBLE_EQ(a.position_mm(), 250.0);  // noise is in the sensor, not in the piston
}

TEST(HammersteinPlant, StateSnapshotReplaysIdentically) {
  auto p = paper_plant({.noise_std_mm = 0.1, .seed = 3});
  for (int k = 0; k < 50; ++k) p.step(3.0);
  const auto snapshot = p.state();
  std::vector<double> first;
  for (int k = 0; k < 100; ++k) { p.step(k % 7 - 3.0); first.push_back(p.measured_v()); }
  p.set_state(snapshot);
  for (int k = 0; k < 100; ++k) { p.step(k % 7 - 3.0); EXPECT_EQ(p.measured_v(), first[static_cast<std::size_t>(k)]); }
}

TEST(HammersteinPlant, NonFiniteCommandIsTakenAsCentredValve) {
  auto p = paper_plant({.initial_position_mm = 100.0});
  p.step(std::nan(""));
  EXPECT_NEAR(p.position_mm(), 100.0, kTol);
}

TEST(HammersteinPlant, RefusesDirectFeedthroughAndBadOptions) {
  auto m = core::paper::model();
  m.B = {0.5, 1.024, -2.046, 1.029};
  auto p = HammersteinPlant::make(m, {});
  ASSERT_FALSE(p.has_value());
  EXPECT_NE(p.error().message.find("B[0]"), std::string::npos);
  auto q = HammersteinPlant::make(core::paper::model(), {.initial_position_mm = 600.0});
  ASSERT_FALSE(q.has_value());
  EXPECT_NE(q.error().message.find("outside the stroke"), std::string::npos);
  auto r = HammersteinPlant::make(core::paper::model(), {.noise_std_mm = -1.0});
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("noise"), std::string::npos);
}

}  // namespace
}  // namespace epa::plant
