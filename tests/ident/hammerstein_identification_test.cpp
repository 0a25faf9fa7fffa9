#include "ident/hammerstein_identification.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/paper_reference.hpp"
#include "ident/arx_metrics.hpp"
#include "ident_test_data.hpp"

namespace epa::ident {
namespace {

using testdata::kPaperDz;

// The paper's plant with 0.1 mm sensor noise: the refinement must keep what the one-step fit had.
constexpr double kBreakPointTolV = 0.001;
constexpr double kSlopeRatioRelTol = 0.005;
constexpr double kValidationFitMinPct = 99.0;

IdentificationOptions small_budget(FitCriterion criterion = FitCriterion::kSimulation) {
  IdentificationOptions o;
  o.search = {.na = {3, 3}, .nb = {2, 4}, .nk = {1, 1}};
  o.swarm.orders = {.na = 3, .nb = 4, .nk = 1};
  o.swarm.particles = 16;
  o.swarm.generations = 25;
  o.swarm.polish_evaluations = 400;
  o.criterion = criterion;
  return o;
}

const std::vector<Segment>& estimation() {
  static const auto s = testdata::paper_segments(1, 60.0, 0.1);
  return s;
}
const std::vector<Segment>& validation() {
  static const auto s = testdata::paper_segments(2, 60.0, 0.1);
  return s;
}

TEST(HammersteinIdentification, ThePapersPlantComesBackWithItsBreakPoints) {
  auto id = identify_hammerstein(estimation(), validation(), small_budget());
  ASSERT_TRUE(id.has_value()) << id.error().message;
  const auto& fit = id->fit;
  EXPECT_EQ(fit.criterion, FitCriterion::kSimulation);
  EXPECT_NEAR(fit.dead_zone.b_r, kPaperDz.b_r, kBreakPointTolV);
  EXPECT_NEAR(fit.dead_zone.b_l, kPaperDz.b_l, kBreakPointTolV);
  EXPECT_NEAR(fit.ratio / (kPaperDz.m_r / kPaperDz.m_l), 1.0, kSlopeRatioRelTol);
  EXPECT_DOUBLE_EQ(fit.dead_zone.m_l, kPaperDz.m_l);  // the normalisation
  EXPECT_EQ(fit.arx.model.orders, (ArxOrders{.na = 3, .nb = 3, .nk = 1}));  // eq 9's order, the fewest within tolerance
  const auto f = fit_percent(fit.arx.model, through_dead_zone(validation(), fit.dead_zone), 0);
  EXPECT_GE(f.simulation_pct, kValidationFitMinPct);
  // The README's "Checks" line quotes these (--gtest_output=json:FILE shows them).
  RecordProperty("validation_fit_pct", std::to_string(f.simulation_pct));
  RecordProperty("break_point_error_V", std::to_string(std::max(std::abs(fit.dead_zone.b_r - kPaperDz.b_r), std::abs(fit.dead_zone.b_l - kPaperDz.b_l))));
  RecordProperty("slope_ratio_error_pct", std::to_string(100.0 * std::abs(fit.ratio / (kPaperDz.m_r / kPaperDz.m_l) - 1.0)));
  ASSERT_TRUE(id->dead_band.has_value());
  EXPECT_TRUE(id->dead_band->right && id->dead_band->left);
  EXPECT_GT(id->swarm_evaluations, 0u);
}

TEST(HammersteinIdentification, TheRefinedModelSimulatesAtLeastAsWellAsTheOneStepFit) {
  auto refined = identify_hammerstein(estimation(), validation(), small_budget());
  auto one_step = identify_hammerstein(estimation(), validation(), small_budget(FitCriterion::kOneStep));
  ASSERT_TRUE(refined.has_value() && one_step.has_value());
  EXPECT_EQ(one_step->fit.criterion, FitCriterion::kOneStep);
  EXPECT_FALSE(one_step->dead_band.has_value());
  auto validation_fit = [&](const HammersteinFit& f) {
    return fit_percent(f.arx.model, through_dead_zone(validation(), f.dead_zone), 0).simulation_pct;
  };
  EXPECT_GE(validation_fit(refined->fit), validation_fit(one_step->fit));
}

TEST(HammersteinIdentification, ASideNeverDrivenBeyondItsBreakPointIsAnError) {
  // Pulses up to 1.6 V never pass b_l = -1.722 V.
  // Centring pulse signs: a sweep heading down on a plant whose left side never moves stays at the
  // top, where only downward pulses are allowed, and then drives neither side (both named then).
  const auto data = testdata::paper_segments(6, 30.0, 0.1, 1.6, false);
  for (auto criterion : {FitCriterion::kSimulation, FitCriterion::kOneStep}) {
    auto id = identify_hammerstein(data, {}, small_budget(criterion));
    ASSERT_FALSE(id.has_value());
    EXPECT_NE(id.error().message.find("the left side of the dead zone is not identified"), std::string::npos)
        << id.error().message;
    EXPECT_NE(id.error().message.find("--amplitude-max"), std::string::npos);
  }
}

}  // namespace
}  // namespace epa::ident
