// The diagnosis's verdict on a gain that changes along the stroke: a position dependence whose
// gain is nominal somewhere is that alone; one whose gain is off everywhere also has a gain
// change (a lower supply with compressibility on top). And on a gain that changes during each run
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

TEST(Selection, AGainOffAlongTheWholeStrokeIsAlsoAGainChange) {
  epa::plant::EffectSet e;
  e.set(EffectKind::kGainChange, {0.6});
  e.set(EffectKind::kPositionDependentGain, {0.0, 0.25});  // 0.6 x (0.7 ... 1.3): below nominal everywhere
  const auto d = diagnose_hidden({e});
  EXPECT_TRUE(named(d, EffectKind::kPositionDependentGain));
  EXPECT_TRUE(named(d, EffectKind::kGainChange));
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
