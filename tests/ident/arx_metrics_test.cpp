#include "ident/arx_metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/paper_reference.hpp"
#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

using testdata::kExactTol;

// y(k) = 0.5 y(k-1) + u(k-1)
const ArxModel kFirstOrder{.orders = {.na = 1, .nb = 1, .nk = 1}, .a = {-0.5}, .b = {1.0}};

TEST(ArxMetrics, OneStepAndFreeRunByHand) {
  const Segment s{.name = "s", .t0_s = 0.0, .y = {1.0, 2.0, 3.0}, .u = {2.0, 0.0, 0.0}};
  const auto p = predict_one_step(kFirstOrder, s, 0);
  EXPECT_DOUBLE_EQ(p[0], 1.0);  // before the first row: the measurement
  EXPECT_DOUBLE_EQ(p[1], 2.5);  // 0.5 * 1 + 2
  EXPECT_DOUBLE_EQ(p[2], 1.0);  // 0.5 * 2 (measured) + 0
  const auto r = simulate_free_run(kFirstOrder, s, 0);
  EXPECT_DOUBLE_EQ(r[1], 2.5);
  EXPECT_DOUBLE_EQ(r[2], 1.25);  // 0.5 * 2.5 (its own past) + 0
}

TEST(ArxMetrics, NrmseFitByHand) {
  // y = 1..4, mean 2.5, |y - mean| = sqrt(5); yhat off by 1 in one sample: fit = 100 (1 - 1/sqrt 5).
  const Segment s{.name = "s", .t0_s = 0.0, .y = {1, 2, 3, 4}, .u = {0, 0, 0, 0}};
  EXPECT_NEAR(nrmse_fit_percent({s}, {{1, 2, 3, 5}}, 0), 100.0 * (1.0 - 1.0 / std::sqrt(5.0)), kExactTol);
  EXPECT_NEAR(nrmse_fit_percent({s}, {{2.5, 2.5, 2.5, 2.5}}, 0), 0.0, kExactTol);  // the mean predicts nothing
  EXPECT_NEAR(nrmse_fit_percent({s}, {{1, 2, 3, 4}}, 0), 100.0, kExactTol);
  // Only samples from `first` on count: from k = 2, mean 3.5, |y - mean| = sqrt(0.5), error 1.
  EXPECT_NEAR(nrmse_fit_percent({s}, {{9, 9, 3, 5}}, 2), 100.0 * (1.0 - 1.0 / std::sqrt(0.5)), kExactTol);
}

TEST(ArxMetrics, InformationCriteriaFormulas) {
  const auto ic = information_criteria(0.01, 100, 4);
  EXPECT_DOUBLE_EQ(ic.loss, 0.01);
  EXPECT_NEAR(ic.fpe, 0.01 * 1.04 / 0.96, 1e-15);
  EXPECT_NEAR(ic.aic, 100.0 * std::log(0.01) + 8.0, 1e-9);
}

TEST(ArxMetrics, TheExactModelFitsAHundredPercent) {
  const auto m = core::paper::model();
  const auto s = testdata::linear_arx_segment(m.A, m.B, 2000, 9);
  const ArxModel model{.orders = {.na = 3, .nb = 3, .nk = 1}, .a = {-0.9094, -0.6110, 0.5204}, .b = {1.024, -2.046, 1.029}};
  const auto f = fit_percent(model, {s}, 0);
  EXPECT_NEAR(f.one_step_pct, 100.0, 1e-6);
  EXPECT_NEAR(f.simulation_pct, 100.0, 1e-6);
}

TEST(ArxMetrics, FreeRunShowsTheGainErrorThatOneStepHides) {
  // The plant integrates: b_3 off by 0.0005 makes B(1), the velocity gain, 7 % too large. One step
  // barely notices; a free run accumulates it.
  const auto m = core::paper::model();
  const auto s = testdata::linear_arx_segment(m.A, m.B, 4000, 2);
  const ArxModel wrong{.orders = {.na = 3, .nb = 3, .nk = 1}, .a = {-0.9094, -0.6110, 0.5204},
                       .b = {1.024, -2.046, 1.029 + 0.0005}};
  const auto f = fit_percent(wrong, {s}, 0);
  EXPECT_GT(f.one_step_pct, 99.9);
  EXPECT_LT(f.simulation_pct, f.one_step_pct - 1.0);
}

// The truth: the paper's model itself, on an excitation run read with 0.1 mm of sensor noise. Its
// free-run fit should not depend on the sample the simulation starts from: the plant integrates,
// so a past taken as measured starts it with the noise of those few samples as a velocity, which
// it keeps as an offset for the whole run.
TEST(ArxMetrics, TheFreeRunFitOfTheTrueModelHardlyMovesWithItsFirstSample) {
  const auto paper = core::paper::model();
  const auto segments = through_dead_zone(testdata::paper_segments(3, 60.0, 0.1), paper.dead_zone);
  const ArxModel model{.orders = {.na = 3, .nb = 3, .nk = 1}, .a = {paper.A[1], paper.A[2], paper.A[3]},
                       .b = {paper.B[1], paper.B[2], paper.B[3]}};
  double lowest = 100.0, highest = -100.0;
  for (std::size_t first = 3; first <= 14; ++first) {
    const double fit = fit_percent(model, segments, first).simulation_pct;
    lowest = std::min(lowest, fit), highest = std::max(highest, fit);
  }
  EXPECT_GT(lowest, 95.0);
  EXPECT_LT(highest - lowest, 0.1) << "from " << lowest << " to " << highest << " %";
}

TEST(ArxMetrics, TheInitialPastOfNoiseFreeDataIsTheMeasuredOne) {
  const auto m = core::paper::model();
  const auto s = testdata::linear_arx_segment(m.A, m.B, 200, 4);
  const ArxModel model{.orders = {.na = 3, .nb = 3, .nk = 1}, .a = {m.A[1], m.A[2], m.A[3]}, .b = {m.B[1], m.B[2], m.B[3]}};
  const auto past = initial_past(model, s, 50);
  ASSERT_EQ(past.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(past[i], s.y[49 - i], 1e-9) << i;
}

TEST(ArxMetrics, ADivergingModelGetsAFiniteNegativeFit) {
  const Segment s = testdata::linear_arx_segment({1.0, -0.5}, {0.0, 1.0}, 3000, 1);
  const ArxModel unstable{.orders = {.na = 1, .nb = 1, .nk = 1}, .a = {-1.5}, .b = {1.0}};
  const auto f = fit_percent(unstable, {s}, 0);
  EXPECT_TRUE(std::isfinite(f.simulation_pct));
  EXPECT_LT(f.simulation_pct, -1e6);
}

}  // namespace
}  // namespace epa::ident
