#include "core/step_metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace epa::core {
namespace {

// Times are whole numbers of samples times Ts, so only the rounding of k * Ts (a few ulps) can
// separate them from the hand-derived value.
constexpr double kTimeTol = 1e-12;
// Percentages and millimetres come from means of a few hundred exact or nearly exact values.
constexpr double kValueTol = 1e-9;

constexpr double kTs = 0.01;  // the sample time used by most cases below: 2 s window = 200 samples

StepMetricsOptions options_with_ts(double Ts) {
  StepMetricsOptions o;
  o.Ts = Ts;
  return o;
}

// y[k] = final * (1 - 0.8^k), k = 0 .. n-1: a first-order approach with no overshoot.
// By hand (0.8^k against 0.9, 0.1 and 0.02):
//   10 %: 0.8^1 = 0.8 <= 0.9                               -> k = 1
//   90 %: 0.8^10 = 0.1074 > 0.1, 0.8^11 = 0.0859 <= 0.1     -> k = 11
//   2 % band: 0.8^17 = 0.0225 > 0.02, 0.8^18 = 0.0180       -> settles at k = 18
// After 200 samples 0.8^k < 1e-19, so the final value is `final` to double precision.
std::vector<double> first_order(double final_value, std::size_t n = 400) {
  std::vector<double> y(n);
  for (std::size_t k = 0; k < n; ++k) y[k] = final_value * (1.0 - std::pow(0.8, static_cast<double>(k)));
  return y;
}

TEST(StepMetrics, RampRiseTimeIsBetweenThe10And90PercentCrossings) {
  // 0 to 100 over 100 samples, then flat: y = 10 first at k = 10, y = 90 first at k = 90.
  std::vector<double> y(400);
  for (std::size_t k = 0; k < y.size(); ++k) y[k] = std::min(static_cast<double>(k), 100.0);
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(kTs));
  EXPECT_TRUE(m.moved);
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.80, kTimeTol);  // (90 - 10) * 0.01
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 0.0, kValueTol);
  EXPECT_NEAR(m.final_mm, 100.0, kValueTol);
  EXPECT_NEAR(m.ess_mm, 0.0, kValueTol);
  ASSERT_TRUE(m.settling_s.has_value());  // the exact value: SampleExactlyOnTheBandEdgeIsInside
}

TEST(StepMetrics, SampleExactlyOnTheBandEdgeIsInside) {
  // The same ramp: the band is |y - final| <= 2 % of the move = 2 mm, and y = 98 at k = 98 is
  // exactly 2 mm from 100, so it is inside; k = 97 (3 mm) is the last sample outside, and the
  // settling time is 98 * 0.01 = 0.98 s. Every number here is exact in binary except Ts.
  std::vector<double> y(400);
  for (std::size_t k = 0; k < y.size(); ++k) y[k] = std::min(static_cast<double>(k), 100.0);
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(kTs));
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.98, kTimeTol);
}

TEST(StepMetrics, FirstOrderResponseSettlesAtTheFirstSampleThatStaysInTheBand) {
  const StepMetrics m = step_metrics(first_order(100.0), 100.0, options_with_ts(kTs));
  EXPECT_TRUE(m.moved);
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.10, kTimeTol);  // (11 - 1) * 0.01
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.18, kTimeTol);  // k = 18
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 0.0, kValueTol);
  EXPECT_NEAR(m.final_mm, 100.0, kValueTol);
  EXPECT_NEAR(m.ess_mm, 0.0, kValueTol);
}

TEST(StepMetrics, OvershootIsThePeakAboveTheFinalValueInPercent) {
  // Peaks at 110 on a final value of 100: 10 %.
  std::vector<double> y = {0.0, 30.0, 60.0, 95.0, 105.0, 110.0, 106.0, 103.0, 101.5};
  y.resize(400, 100.0);
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(kTs));
  EXPECT_TRUE(m.moved);
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 10.0, kValueTol);
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.02, kTimeTol);  // 10 % at k = 1 (30), 90 % at k = 3 (95)
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.08, kTimeTol);  // last outside |y - 100| <= 2 is k = 7 (103)
}

TEST(StepMetrics, ResponseThatNeverMovesHasNoRiseSettlingOrOvershoot) {
  const std::vector<double> y(4000, 0.0);
  const StepMetrics m = step_metrics(y, 25.0);
  EXPECT_FALSE(m.moved);
  EXPECT_FALSE(m.rise_s.has_value());
  EXPECT_FALSE(m.settling_s.has_value());
  EXPECT_FALSE(m.overshoot_pct.has_value());
  EXPECT_NEAR(m.ess_mm, 25.0, kValueTol);
  EXPECT_NEAR(m.final_mm, 0.0, kValueTol);
}

TEST(StepMetrics, MoveSmallerThanTheBandDoesNotCountAsMoved) {
  // Final 0.5 mm on a 50 mm step: below 2 % of 50 = 1 mm.
  std::vector<double> y(400, 0.5);
  y[0] = 0.0;
  const StepMetrics m = step_metrics(y, 50.0, options_with_ts(kTs));
  EXPECT_FALSE(m.moved);
  EXPECT_FALSE(m.rise_s.has_value());
  EXPECT_FALSE(m.overshoot_pct.has_value());
  EXPECT_NEAR(m.ess_mm, 49.5, kValueTol);
}

TEST(StepMetrics, DownwardStepHasPositiveRiseAndCountsUndershootAsOvershoot) {
  // From 100 down to 50 (a move of -50), dipping to 45: 5 / 50 = 10 % past the final value.
  std::vector<double> y = {100.0, 80.0, 60.0, 45.0, 48.5};
  y.resize(400, 50.0);
  const StepMetrics m = step_metrics(y, 50.0, options_with_ts(kTs));
  EXPECT_TRUE(m.moved);
  ASSERT_TRUE(m.rise_s.has_value());
  // 10 % of the move (y <= 95) first at k = 1; 90 % (y <= 55) first at k = 3.
  EXPECT_NEAR(*m.rise_s, 0.02, kTimeTol);
  EXPECT_GT(*m.rise_s, 0.0);
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 10.0, kValueTol);
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.05, kTimeTol);  // band +-1 mm: k = 4 (48.5) is the last outside
  EXPECT_NEAR(m.final_mm, 50.0, kValueTol);
  EXPECT_NEAR(m.ess_mm, 0.0, kValueTol);
}

TEST(StepMetrics, DownwardFirstOrderStepMirrorsTheUpwardOne) {
  std::vector<double> y = first_order(-50.0);
  for (double& v : y) v += 100.0;  // 100 -> 50
  const StepMetrics m = step_metrics(y, 50.0, options_with_ts(kTs));
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.10, kTimeTol);
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.18, kTimeTol);
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 0.0, kValueTol);
}

TEST(StepMetrics, StillOscillatingOutsideTheBandAtTheLastSampleHasNoSettlingTime) {
  // y = 100 +- 5 alternating after the step: the mean over the (even) window is 100, every
  // sample is 5 mm from it, more than the 2 mm band.
  std::vector<double> y(400);
  y[0] = 0.0;
  for (std::size_t k = 1; k < y.size(); ++k) y[k] = (k % 2 == 0) ? 105.0 : 95.0;
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(kTs));
  EXPECT_TRUE(m.moved);
  EXPECT_NEAR(m.final_mm, 100.0, kValueTol);
  EXPECT_FALSE(m.settling_s.has_value());
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 5.0, kValueTol);
}

TEST(StepMetrics, LastSampleOutsideTheBandHasNoSettlingTime) {
  std::vector<double> y = first_order(100.0);
  y.back() = 110.0;  // final = 100 + 10/200 = 100.05; band 2.001; last sample 9.95 away
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(kTs));
  EXPECT_NEAR(m.final_mm, 100.05, kValueTol);
  EXPECT_FALSE(m.settling_s.has_value());
}

TEST(StepMetrics, SteadyStateWindowIsTheLastTwoSeconds) {
  // Default Ts = 0.005: 2 s = 400 samples. The last 200 sit at 99 (e = 1), the 200 before at
  // 97 (e = 3), everything earlier at 90 (e = 10, outside the window).
  std::vector<double> y(2000, 90.0);
  y[0] = 0.0;
  for (std::size_t k = 1600; k < 1800; ++k) y[k] = 97.0;
  for (std::size_t k = 1800; k < 2000; ++k) y[k] = 99.0;
  const StepMetrics m = step_metrics(y, 100.0);
  EXPECT_NEAR(m.ess_mm, 2.0, kValueTol);     // (200 * 1 + 200 * 3) / 400
  EXPECT_NEAR(m.final_mm, 98.0, kValueTol);  // (200 * 99 + 200 * 97) / 400
}

TEST(StepMetrics, SteadyStateWindowFollowsTheOption) {
  std::vector<double> y(2000, 90.0);
  y[0] = 0.0;
  for (std::size_t k = 1600; k < 1800; ++k) y[k] = 97.0;
  for (std::size_t k = 1800; k < 2000; ++k) y[k] = 99.0;
  StepMetricsOptions o;  // Ts = 0.005
  o.ess_window_s = 1.0;  // 200 samples: only the 99s
  const StepMetrics m = step_metrics(y, 100.0, o);
  EXPECT_NEAR(m.ess_mm, 1.0, kValueTol);
  EXPECT_NEAR(m.final_mm, 99.0, kValueTol);
}

TEST(StepMetrics, SteadyStateErrorIsMeanAbsoluteErrorNotAbsoluteMeanError) {
  // Alternating 98 / 102 around r = 100: mean error 0, mean |error| 2.
  std::vector<double> y(400);
  y[0] = 0.0;
  for (std::size_t k = 1; k < y.size(); ++k) y[k] = (k % 2 == 0) ? 102.0 : 98.0;
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(kTs));
  EXPECT_NEAR(m.ess_mm, 2.0, kValueTol);
  EXPECT_NEAR(m.final_mm, 100.0, kValueTol);
}

TEST(StepMetrics, StalledResponseMeasuresRiseAgainstTheFinalValue) {
  // Stalls at 12.5 on a 50 mm reference. Against the final value (docs/paper.md: stepinfo
  // conventions) the 10-90 % rise is the same as for any first-order approach, 0.10 s; against
  // the reference, 90 % (45 mm) would never be reached.
  const StepMetrics m = step_metrics(first_order(12.5), 50.0, options_with_ts(kTs));
  EXPECT_TRUE(m.moved);  // 12.5 > 2 % of 50 = 1
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.10, kTimeTol);
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.18, kTimeTol);
  EXPECT_NEAR(m.final_mm, 12.5, kValueTol);
  EXPECT_NEAR(m.ess_mm, 37.5, kValueTol);
  ASSERT_TRUE(m.overshoot_pct.has_value());
  EXPECT_NEAR(*m.overshoot_pct, 0.0, kValueTol);
}

TEST(StepMetrics, TimesScaleWithTheSampleTime) {
  // Same samples at Ts = 0.005 s: every time halves.
  std::vector<double> y = first_order(100.0, 800);
  const StepMetrics m = step_metrics(y, 100.0, options_with_ts(0.005));
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.05, kTimeTol);
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.09, kTimeTol);
}

TEST(StepMetrics, NonZeroStartPositionIsTheOrigin) {
  // From 20 to 120: the same shape shifted by 20 mm gives the same times.
  std::vector<double> y = first_order(100.0);
  for (double& v : y) v += 20.0;
  const StepMetrics m = step_metrics(y, 120.0, options_with_ts(kTs));
  ASSERT_TRUE(m.rise_s.has_value());
  EXPECT_NEAR(*m.rise_s, 0.10, kTimeTol);
  ASSERT_TRUE(m.settling_s.has_value());
  EXPECT_NEAR(*m.settling_s, 0.18, kTimeTol);
  EXPECT_NEAR(m.final_mm, 120.0, kValueTol);
}

TEST(StepMetrics, EmptyResponseHasNoMetrics) {
  const std::vector<double> y;
  const StepMetrics m = step_metrics(y, 50.0);
  EXPECT_FALSE(m.moved);
  EXPECT_FALSE(m.rise_s.has_value());
  EXPECT_FALSE(m.settling_s.has_value());
  EXPECT_FALSE(m.overshoot_pct.has_value());
}

}  // namespace
}  // namespace epa::core
