#include "report/effect_shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/paper_reference.hpp"

namespace {

using epa::plant::EffectKind;

epa::diag::Diagnosis diagnosis_naming(EffectKind kind, epa::plant::EffectParams params) {
  epa::diag::Diagnosis d;
  d.nominal.model = epa::core::paper::model();
  d.final_model = d.nominal;
  d.final_model.effects.set(kind, params);
  d.effects = {kind};
  return d;
}

double at(const epa::report::Series& s, double x) {
  for (std::size_t i = 0; i < s.x.size(); ++i)
    if (std::abs(s.x[i] - x) < 1e-6) return s.y[i];
  ADD_FAILURE() << "no point at " << x;
  return 0.0;
}

TEST(EffectShapes, AChamberSlopeFallsAlongTheStrokeEachWayAndIsMirrored) {
  const auto panels = epa::report::effect_shape_panels(diagnosis_naming(EffectKind::kPositionDependentGain, {0.0, 0.2, 0.0}));
  ASSERT_EQ(panels.size(), 1u);
  const auto& extending = panels[0].series[0];
  const auto& retracting = panels[0].series[1];
  EXPECT_NEAR(at(extending, 250.0), 1.0, 1e-9);
  EXPECT_NEAR(at(extending, 150.0), 1.2, 1e-9);  // the driving chamber 100 mm shorter: 20 % more gain
  EXPECT_NEAR(at(extending, 350.0), 0.8, 1e-9);
  EXPECT_NEAR(at(retracting, 150.0), 0.8, 1e-9);
  EXPECT_NEAR(at(retracting, 350.0), 1.2, 1e-9);
}

// Beside a position dependence the drive's re-fitted gain is not named: it is the curve's level.
TEST(EffectShapes, TheGainAlongTheStrokeCarriesTheRefittedGainAsItsLevel) {
  auto d = diagnosis_naming(EffectKind::kPositionDependentGain, {0.0, 0.2, 0.0});
  d.final_model.effects.set(EffectKind::kGainChange, {0.7});
  const auto panels = epa::report::effect_shape_panels(d);
  ASSERT_EQ(panels.size(), 1u);
  EXPECT_NEAR(at(panels[0].series[0], 250.0), 0.7, 1e-9);
  EXPECT_NEAR(at(panels[0].series[0], 150.0), 0.7 * 1.2, 1e-9);
  EXPECT_NEAR(at(panels[0].series[1], 150.0), 0.7 * 0.8, 1e-9);
}

TEST(EffectShapes, FrictionIsCoulombAgainstTheSpeedWhileSlidingAndHoldsUpToBreakawayWhileSticking) {
  const auto panels = epa::report::effect_shape_panels(diagnosis_naming(EffectKind::kStaticFriction, {0.6, 0.3, 0.0}));
  ASSERT_EQ(panels.size(), 1u);
  const auto& sliding = panels[0].series[0];
  const auto& sticking = panels[0].series[1];
  EXPECT_NEAR(at(sliding, 50.0), 0.3, 1e-9);
  EXPECT_NEAR(at(sliding, -20.0), -0.3, 1e-9);
  ASSERT_EQ(sticking.y.size(), 2u);
  EXPECT_NEAR(sticking.y[0], -0.6, 1e-9);
  EXPECT_NEAR(sticking.y[1], 0.6, 1e-9);
}

TEST(EffectShapes, ALagIsTheSpoolsStepAndQuantisationHasNoPanel) {
  auto d = diagnosis_naming(EffectKind::kValveLag, {0.02, 0.0, 0.0});
  const auto panels = epa::report::effect_shape_panels(d);
  ASSERT_EQ(panels.size(), 1u);
  const auto& spool = panels[0].series[1];
  EXPECT_NEAR(at(spool, 20.0), 1.0 - std::exp(-5.0 * 0.005 / 0.02), 1e-9);  // 5 samples at 5 ms, 1 - e^(-t/tau) after the 1st
  EXPECT_TRUE(epa::report::effect_shape_panels(diagnosis_naming(EffectKind::kSensorQuantization, {1.0, 0.0, 0.0})).empty());
}

TEST(EffectShapes, AGainThatDriftsIsDrawnAgainstTheRunsTimeBesideTheSpeedMap) {
  const auto holds = epa::report::effect_shape_panels(diagnosis_naming(EffectKind::kGainChange, {0.8, 1.0, 0.0}));
  ASSERT_EQ(holds.size(), 1u);  // the speed map alone
  const auto panels = epa::report::effect_shape_panels(diagnosis_naming(EffectKind::kGainChange, {0.8, 1.0, -0.01, 1000.0}));
  ASSERT_EQ(panels.size(), 2u);
  EXPECT_EQ(panels[1].x_label, "time since the run started (s)");
  const auto& gain = panels[1].series[1];
  EXPECT_NEAR(at(gain, 0.0), 0.8, 1e-12);
  EXPECT_NEAR(at(gain, 10.0), 0.8 * (1.0 - 0.01 * 1000.0 * -std::expm1(-10.0 / 1000.0)), 1e-12);  // 0.7204: settling in 1000 s
}

}  // namespace
