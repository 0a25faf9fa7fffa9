#include "ident/arx_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"
#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

using testdata::kNoiseFreeTol;
using testdata::kExactTol;
using testdata::max_abs_diff;

TEST(ArxEstimator, FirstOrderHandExample) {
  // y(k) = 0.5 y(k-1) + 2 u(k-1): A = 1 - 0.5q, B = 2q, so a_1 = -0.5, b_1 = 2.
  const auto s = testdata::linear_arx_segment({1.0, -0.5}, {0.0, 2.0}, 200, 3);
  auto e = estimate_arx({s}, {.na = 1, .nb = 1, .nk = 1});
  ASSERT_TRUE(e.has_value()) << e.error().message;
  EXPECT_NEAR(e->model.a[0], -0.5, kExactTol);
  EXPECT_NEAR(e->model.b[0], 2.0, kExactTol);
  EXPECT_NEAR(e->loss, 0.0, kExactTol);
  EXPECT_EQ(e->N, 199u);  // rows k = 1..199
}

TEST(ArxEstimator, NoiseFreeDataGiveThePapersCoefficientsWithin1e6) {
  // The paper's eq 9 driven directly (u_d known): two runs, estimated together.
  const auto m = core::paper::model();
  const std::vector<Segment> runs = {testdata::linear_arx_segment(m.A, m.B, 3000, 1, "a"),
                                     testdata::linear_arx_segment(m.A, m.B, 2000, 2, "b")};
  auto e = estimate_arx(runs, {.na = 3, .nb = 3, .nk = 1});
  ASSERT_TRUE(e.has_value()) << e.error().message;
  EXPECT_LT(max_abs_diff(e->model.A(), m.A), kNoiseFreeTol);
  EXPECT_LT(max_abs_diff(e->model.B(), m.B), kNoiseFreeTol);
  EXPECT_EQ(e->rank, 6u);
}

TEST(ArxEstimator, RegressorsNeverCrossARunBoundary) {
  const auto A = testdata::stable_A(), B = testdata::stable_B();
  Segment a = testdata::linear_arx_segment(A, B, 400, 5, "a");
  Segment b = testdata::linear_arx_segment(A, B, 400, 6, "b");
  // b starts mid-trajectory: its first rows only make sense with its own past.
  b.y.erase(b.y.begin(), b.y.begin() + 50);
  b.u.erase(b.u.begin(), b.u.begin() + 50);
  auto separate = estimate_arx({a, b}, {.na = 3, .nb = 3, .nk = 1});
  ASSERT_TRUE(separate.has_value());
  EXPECT_LT(max_abs_diff(separate->model.A(), A), kNoiseFreeTol);

  Segment joined = a;  // the same samples glued into one run: rows at the seam mix the two runs
  joined.y.insert(joined.y.end(), b.y.begin(), b.y.end());
  joined.u.insert(joined.u.end(), b.u.begin(), b.u.end());
  auto glued = estimate_arx({joined}, {.na = 3, .nb = 3, .nk = 1});
  ASSERT_TRUE(glued.has_value());
  EXPECT_GT(max_abs_diff(glued->model.A(), A), 1e-4);
  EXPECT_EQ(separate->N + 3, glued->N);  // the seam's 3 rows are the difference
}

TEST(ArxEstimator, RowsStartAtTheLargestLag) {
  // na = 2, nb = 3, nk = 2: the oldest regressor is u(k - 4), so rows start at k = 4.
  const ArxOrders o{.na = 2, .nb = 3, .nk = 2};
  EXPECT_EQ(o.first_row(), 4u);
  const auto A = testdata::stable_A();
  const core::Polynomial B{0.0, 0.0, 0.5, 0.2, 0.1};
  auto reg = ArxRegression::make({testdata::linear_arx_segment(A, B, 100, 1), testdata::linear_arx_segment(A, B, 50, 2)}, o);
  ASSERT_TRUE(reg.has_value());
  EXPECT_EQ(reg->rows(), 96u + 46u);
}

TEST(ArxEstimator, DelayPadsBWithLeadingZeros) {
  const ArxModel m{.orders = {.na = 1, .nb = 2, .nk = 3}, .a = {-0.5}, .b = {1.0, 2.0}};
  EXPECT_EQ(m.B().coefficients(), (std::vector<double>{0.0, 0.0, 0.0, 1.0, 2.0}));
  EXPECT_EQ(m.A().coefficients(), (std::vector<double>{1.0, -0.5}));
}

TEST(ArxEstimator, DelayedPlantIsFoundAtItsDelay) {
  const auto A = testdata::stable_A();
  const core::Polynomial B{0.0, 0.0, 0.5, 0.2};  // nk = 2, nb = 2
  auto e = estimate_arx({testdata::linear_arx_segment(A, B, 800, 4)}, {.na = 3, .nb = 2, .nk = 2});
  ASSERT_TRUE(e.has_value());
  EXPECT_LT(max_abs_diff(e->model.B(), B), kNoiseFreeTol);
}

TEST(ArxEstimator, AnInputThatNeverMovesIsNotExcitation) {
  Segment s = testdata::linear_arx_segment(testdata::stable_A(), testdata::stable_B(), 300, 1);
  std::fill(s.u.begin(), s.u.end(), 0.0);
  auto e = estimate_arx({s}, {.na = 3, .nb = 3, .nk = 1});
  ASSERT_FALSE(e.has_value());
  EXPECT_EQ(e.error().code, core::ErrorCode::kNumerical);
  EXPECT_NE(e.error().message.find("do not excite"), std::string::npos) << e.error().message;
  EXPECT_NE(e.error().message.find("epa excite"), std::string::npos);
}

TEST(ArxEstimator, TooFewSamplesSayHowManyAreNeeded) {
  Segment s = testdata::linear_arx_segment(testdata::stable_A(), testdata::stable_B(), 8, 1);
  auto e = estimate_arx({s}, {.na = 3, .nb = 3, .nk = 1});
  ASSERT_FALSE(e.has_value());
  EXPECT_NE(e.error().message.find("5 regression rows for 6 parameters"), std::string::npos) << e.error().message;
}

TEST(ArxEstimator, ZeroDelayIsRefusedWithTheReason) {
  auto s = ArxOrders{.na = 2, .nb = 2, .nk = 0}.validate();
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("nk = 0"), std::string::npos);
  EXPECT_FALSE((ArxOrders{.na = 7, .nb = 1, .nk = 1}.validate().has_value()));  // above kMaxModelOrder
  EXPECT_FALSE((ArxOrders{.na = 2, .nb = 5, .nk = 3}.validate().has_value()));  // B of order 7
}

TEST(ArxEstimator, ThroughDeadZoneAppliesEq2) {
  const core::DeadZone dz{.m_r = 2.0, .m_l = 0.5, .b_r = 1.0, .b_l = -1.0};
  const Segment s{.name = "s", .t0_s = 0.0, .y = {0, 0, 0, 0}, .u = {2.0, 0.5, -0.5, -3.0}};
  const auto out = through_dead_zone({s}, dz);
  EXPECT_EQ(out[0].u, (std::vector<double>{2.0, 0.0, 0.0, -1.0}));  // 2 (2 - 1); 0; 0; 0.5 (-3 + 1)
  EXPECT_EQ(out[0].y, s.y);
}

}  // namespace
}  // namespace epa::ident
