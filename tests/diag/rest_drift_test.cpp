#include "diag/rest_drift.hpp"

#include <gtest/gtest.h>

#include "core/random.hpp"

// Runs written here from a plain picture, not from the diagnosis's model: the piston moves at
// 100 mm/s per volt beyond a break point and stands still otherwise; the valve alternates 0.3 s
// pushes with rests of 0.6 s; the sensor adds noise, and optionally a drifting offset or spikes.
namespace {

const epa::core::DeadZone kBand{.m_r = 1.0, .m_l = 1.0, .b_r = 1.2, .b_l = -1.7};

struct Sensor {
  double noise_mm = 0.1, drift_mm_s = 0.0, spike_probability = 0.0;
};

epa::core::Run pushes_and_rests(const Sensor& sensor, int pushes, std::uint64_t seed) {
  epa::core::Random rng(seed);
  epa::core::Run r;
  r.Ts = 0.005;
  double x = 250.0;
  int k = 0;
  auto emit = [&](double u) {
    const double t = k * r.Ts;
    if (u > kBand.b_r) x += 100.0 * (u - kBand.b_r) * r.Ts;
    if (u < kBand.b_l) x += 100.0 * (u - kBand.b_l) * r.Ts;
    double y = x + sensor.noise_mm * rng.normal() + sensor.drift_mm_s * t;
    if (rng.uniform() < sensor.spike_probability) y += (rng.uniform() < 0.5 ? -1.0 : 1.0) * (5.0 + 15.0 * rng.uniform());
    r.t_s.push_back(t), r.y_mm.push_back(y), r.u_V.push_back(u);
    ++k;
  };
  for (int p = 0; p < pushes; ++p) {
    const double u = (p % 2 ? -2.2 : 1.8) + 0.3 * rng.uniform();
    for (int i = 0; i < 60; ++i) emit(u);
    for (int i = 0; i < 120; ++i) emit(0.05 * rng.normal());  // a closed valve's small command
  }
  return r;
}

TEST(RestDrift, ReadingsThatStayPutAtRestAreNotMotion) {
  const auto a = pushes_and_rests({}, 8, 1), b = pushes_and_rests({}, 8, 2);
  const auto d = epa::diag::rest_drift({&a, &b}, kBand, 0.1);
  EXPECT_EQ(d.rests, 16u);
  EXPECT_FALSE(d.moving);
  EXPECT_LT(d.median_speed_mm_s, 0.3);
  EXPECT_GE(d.threshold_mm_s, 0.5);
}

TEST(RestDrift, ASensorWhoseOffsetDriftsIsSeenAtRestAtItsRate) {
  const auto a = pushes_and_rests({.drift_mm_s = 1.5}, 8, 3), b = pushes_and_rests({.drift_mm_s = 1.5}, 8, 4);
  const auto d = epa::diag::rest_drift({&a, &b}, kBand, 0.1);
  EXPECT_TRUE(d.moving);
  EXPECT_NEAR(d.median_speed_mm_s, 1.5, 0.3);
}

TEST(RestDrift, SpikesOfTheSensorAreNeitherMotionNorHideIt) {
  const auto still = pushes_and_rests({.spike_probability = 0.02}, 10, 5);
  EXPECT_FALSE(epa::diag::rest_drift({&still}, kBand, 0.1).moving);
  const auto drifting = pushes_and_rests({.drift_mm_s = 1.5, .spike_probability = 0.02}, 10, 6);
  const auto d = epa::diag::rest_drift({&drifting}, kBand, 0.1);
  EXPECT_TRUE(d.moving);
  EXPECT_NEAR(d.median_speed_mm_s, 1.5, 0.3);
}

TEST(RestDrift, TheMotionOfPushesIsNotCountedAndTooFewRestsGiveNoVerdict) {
  // Pushes move the piston by 20-50 mm; only the rests after them are measured.
  const auto many = pushes_and_rests({}, 12, 7);
  EXPECT_FALSE(epa::diag::rest_drift({&many}, kBand, 0.1).moving);
  const auto two = pushes_and_rests({.drift_mm_s = 3.0}, 2, 8);
  const auto d = epa::diag::rest_drift({&two}, kBand, 0.1);
  EXPECT_EQ(d.rests, 2u);
  EXPECT_FALSE(d.moving);
}

TEST(RestDrift, ACoarseSensorRaisesTheThreshold) {
  // With 2 mm of noise a rest's speed is known to about 2.7 mm/s; 1.5 mm/s is no finding then.
  const auto noisy = pushes_and_rests({.noise_mm = 2.0, .drift_mm_s = 1.5}, 10, 9);
  const auto d = epa::diag::rest_drift({&noisy}, kBand, 2.0);
  EXPECT_GT(d.threshold_mm_s, 3.0);
  EXPECT_FALSE(d.moving);
}

}  // namespace
