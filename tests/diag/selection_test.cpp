// The diagnosis's verdict on a gain that changes along the stroke: a position dependence, whose
// level (nominal somewhere along the stroke or off everywhere) is part of its fitted shape; a gain
// that drifts during each run is a gain change beside it. And on a gain that changes during each run
// (a sagging supply): a gain change, drifting; an effect fitted to where it does nothing is not named.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "diag/selection.hpp"
#include "diag_test_data.hpp"

namespace {

using epa::plant::EffectKind;

bool named(const epa::diag::Diagnosis& d, EffectKind k) { return std::find(d.effects.begin(), d.effects.end(), k) != d.effects.end(); }

epa::diag::Diagnosis diagnose_hidden(const epa::testing::Hidden& hidden) {
  const epa::diag::ReplayModel nominal{epa::core::paper::model(), {}, 500};
  const auto c = epa::testing::make_case(hidden, 5, 4, 2, 10.0, 0.0);
  return epa::diag::diagnose(nominal, epa::testing::pointers(c.train), epa::testing::pointers(c.heldout), {});
}

TEST(Selection, AGainNominalSomewhereAlongTheStrokeIsThePositionDependenceAlone) {
  epa::plant::EffectSet e;
  e.set(EffectKind::kPositionDependentGain, {0.0, 0.25});  // compressibility: nominal at mid-stroke
  const auto d = diagnose_hidden({e});
  EXPECT_TRUE(named(d, EffectKind::kPositionDependentGain));
  EXPECT_FALSE(named(d, EffectKind::kGainChange));
}

// The fitted gain relative to nominal at x, one direction: the drive's gain (at a run's start) times
// the position dependence, as the report's shape draws it.
double gain_at(const epa::plant::EffectSet& e, double direction, double x_mm) {
  const epa::plant::DriveEffects drive(e, epa::core::DeadZone{.m_r = 1.0, .m_l = 1.0, .b_r = 0.0, .b_l = 0.0}, 0.0, 0.0);
  return drive.gain_at(0.0) * drive.finish(direction, x_mm) / direction;
}

// A gain that holds beside a position dependence is that dependence's level: the runs cannot tell a
// lower supply with compressibility on top from a gain lower along the stroke they work in, so the
// level goes into the position family's shape, where it is measured, and no gain change is named.
TEST(Selection, AGainOffAlongTheWholeStrokeIsThePositionDependenceAtItsLevel) {
  epa::plant::EffectSet e;
  e.set(EffectKind::kGainChange, {0.6});
  e.set(EffectKind::kPositionDependentGain, {0.0, 0.25});  // 0.6 x (0.7 ... 1.3): below nominal everywhere
  const auto d = diagnose_hidden({e});
  EXPECT_EQ(d.effects, std::vector<EffectKind>{EffectKind::kPositionDependentGain});
  EXPECT_FALSE(d.unexplained);
  for (double x_mm : {150.0, 250.0, 350.0})
    for (double direction : {1.0, -1.0})
      EXPECT_NEAR(gain_at(d.final_model.effects, direction, x_mm), gain_at(e, direction, x_mm), 0.03)
          << "x " << x_mm << " mm, direction " << direction;
}

// A gain that drifts during each run is a gain change whatever the stroke does.
TEST(Selection, ASagBesideAPositionDependenceIsStillAGainChange) {
  epa::testing::Hidden h;
  h.sagging_supply_bar = 4.2;
  h.effects.set(EffectKind::kPositionDependentGain, {0.0, 0.25});
  const auto d = diagnose_hidden(h);
  EXPECT_TRUE(named(d, EffectKind::kPositionDependentGain));
  EXPECT_TRUE(named(d, EffectKind::kGainChange));
  EXPECT_LT(d.final_model.effects.param(EffectKind::kGainChange, 2), -0.005) << "drift_per_s";
}

// The truth: supply pressure sagging exponentially, flow by the square-root law; the fit: a gain
// linear in time. Over the 10-s runs the flow falls to 87 % of its start.
TEST(Selection, ASupplyThatSagsDuringEachRunIsAGainChangeThatDrifts) {
  epa::testing::Hidden h;
  h.sagging_supply_bar = 4.2;
  ASSERT_LT(epa::testing::sagging_supply_flow_ratio(4.2, 10.0), 0.9);
  const auto d = diagnose_hidden(h);
  EXPECT_EQ(d.effects, std::vector<EffectKind>{EffectKind::kGainChange});
  EXPECT_FALSE(d.unexplained);
  const auto& gain = d.final_model.effects.params(EffectKind::kGainChange);
  EXPECT_LT(gain[2], -0.005) << "drift_per_s";  // the flow falls 1.3 %/s over a run, less as it settles
  EXPECT_GT(gain[0], 0.93) << "gain_ratio at a run's start";
}

TEST(Selection, AGainThatHoldsDoesNotDrift) {
  epa::testing::Hidden h;
  h.effects.set(EffectKind::kGainChange, {0.8});
  const auto d = diagnose_hidden(h);
  EXPECT_EQ(d.effects, std::vector<EffectKind>{EffectKind::kGainChange});
  const auto& gain = d.final_model.effects.params(EffectKind::kGainChange);
  EXPECT_NEAR(gain[0], 0.8, 0.03);
  EXPECT_LT(std::abs(gain[2]) * 10.0, 0.02) << "drift_per_s " << gain[2] << ": the gain moves by that times 10 s in a run";
}

}  // namespace
