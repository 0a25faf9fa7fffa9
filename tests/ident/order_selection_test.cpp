#include "ident/order_selection.hpp"

#include <gtest/gtest.h>

#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

const ArxOrders& orders_of(const OrderSelection& s, std::size_t i) { return s.candidates[i].estimate.model.orders; }

TEST(OrderRange, ParsesOrdersAndRanges) {
  auto r = parse_order_range("1:4", "--na");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->lo, 1);
  EXPECT_EQ(r->hi, 4);
  r = parse_order_range("3", "--nb");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->lo, 3);
  EXPECT_EQ(r->hi, 3);
  for (const char* bad : {"", "a", "1:", "1-4", "2:x", "1:4:5"}) {
    auto e = parse_order_range(bad, "--nk");
    ASSERT_FALSE(e.has_value()) << bad;
    EXPECT_NE(e.error().message.find("--nk"), std::string::npos);
  }
  auto empty = parse_order_range("4:1", "--na");
  ASSERT_FALSE(empty.has_value());
  EXPECT_NE(empty.error().message.find("empty"), std::string::npos);
}

TEST(OrderSelection, NoiseFreeDataRecommendTheGeneratingOrder) {
  const auto A = testdata::stable_A(), B = testdata::stable_B();  // na = 3, nb = 3, nk = 1
  const std::vector<Segment> est = {testdata::linear_arx_segment(A, B, 1500, 1)};
  const std::vector<Segment> val = {testdata::linear_arx_segment(A, B, 1500, 2)};
  auto sel = select_order(est, val, {});
  ASSERT_TRUE(sel.has_value()) << sel.error().message;
  // 4 x 4 x 2 orders; with exact data the largest ones have rank-deficient regressions.
  EXPECT_EQ(sel->candidates.size() + sel->skipped.size(), 32u);
  ASSERT_FALSE(sel->skipped.empty());
  EXPECT_EQ(sel->skipped[0].rfind("na=4 nb=4 nk=1: rank-deficient", 0), 0u) << sel->skipped[0];
  EXPECT_EQ(orders_of(*sel, sel->recommended), (ArxOrders{.na = 3, .nb = 3, .nk = 1}));
  EXPECT_NEAR(sel->candidates[sel->recommended].validation->simulation_pct, 100.0, 1e-6);
  EXPECT_NE(sel->reason.find("validation free-run fit"), std::string::npos) << sel->reason;
  // Larger orders fit exactly too: parsimony decides.
  for (const auto& c : sel->candidates) {
    if (c.estimate.model.orders == ArxOrders{.na = 3, .nb = 4, .nk = 1}) {
      EXPECT_NEAR(c.validation->simulation_pct, 100.0, 1e-6);
    }
  }
}

TEST(OrderSelection, FindsTheDelay) {
  const auto A = testdata::stable_A();
  const core::Polynomial B{0.0, 0.0, 0.5, 0.2};  // nk = 2, nb = 2
  auto sel = select_order({testdata::linear_arx_segment(A, B, 1500, 3)}, {testdata::linear_arx_segment(A, B, 1500, 4)}, {});
  ASSERT_TRUE(sel.has_value());
  EXPECT_EQ(orders_of(*sel, sel->recommended), (ArxOrders{.na = 3, .nb = 2, .nk = 2}));
}

TEST(OrderSelection, WithoutValidationItRanksOnEstimationDataAndSaysSo) {
  const std::vector<Segment> est = {testdata::linear_arx_segment(testdata::stable_A(), testdata::stable_B(), 1000, 1)};
  auto sel = select_order(est, {}, {.na = {2, 3}, .nb = {2, 3}, .nk = {1, 1}});
  ASSERT_TRUE(sel.has_value());
  EXPECT_FALSE(sel->candidates[0].validation.has_value());
  EXPECT_NE(sel->reason.find("No validation run"), std::string::npos);
  EXPECT_NE(format_order_table(*sel).find("<- recommended"), std::string::npos);
}

TEST(OrderSelection, EveryCandidateScoresTheSameSamples) {
  const OrderSearch s{.na = {1, 4}, .nb = {1, 4}, .nk = {1, 2}};
  EXPECT_EQ(common_first_row(s), 5u);  // nk + nb - 1 = 2 + 4 - 1
  auto sel = select_order({testdata::linear_arx_segment(testdata::stable_A(), testdata::stable_B(), 500, 1)}, {}, s);
  ASSERT_TRUE(sel.has_value());
  EXPECT_EQ(sel->first, 5u);
  for (const auto& c : sel->candidates) EXPECT_EQ(c.estimate.N, 495u);
}

TEST(OrderSelection, ParsimonyThenAicDecideAmongEquallyGoodFits) {
  // With a huge tolerance every order counts as "as good as the best": the fewest parameters win
  // (d = 2: na = nb = 1, at either delay), and of those the one with the lower AIC.
  const std::vector<Segment> est = {testdata::linear_arx_segment(testdata::stable_A(), testdata::stable_B(), 1000, 1)};
  auto sel = select_order(est, {}, {.na = {1, 3}, .nb = {1, 3}, .nk = {1, 2}, .tolerance_pct = 1e12});
  ASSERT_TRUE(sel.has_value());
  const auto& r = sel->candidates[sel->recommended];
  EXPECT_EQ(r.estimate.model.orders.d(), 2);
  for (const auto& c : sel->candidates) {
    if (c.estimate.model.orders.d() == 2 && !c.cancels) {
      EXPECT_GE(c.criteria.aic, r.criteria.aic);
    }
  }
}

TEST(OrderSelection, PoleZeroDistanceByHand) {
  // A = 1 - 0.5q: pole 0.5. B = q (1 - 0.4q): zero 0.4 (the delay's zero at z = 0 is not counted).
  const ArxModel m{.orders = {.na = 1, .nb = 2, .nk = 1}, .a = {-0.5}, .b = {1.0, -0.4}};
  EXPECT_NEAR(pole_zero_distance(m), 0.1, 1e-12);
  const ArxModel no_zero{.orders = {.na = 1, .nb = 1, .nk = 1}, .a = {-0.5}, .b = {1.0}};
  EXPECT_TRUE(std::isinf(pole_zero_distance(no_zero)));
}

}  // namespace
}  // namespace epa::ident
