// The diagnosis's verdict on a gain that changes along the stroke: a position dependence whose
// gain is nominal somewhere is that alone; one whose gain is off everywhere also has a gain
// change (a lower supply with compressibility on top).
#include <gtest/gtest.h>

#include <algorithm>

#include "diag/selection.hpp"
#include "diag_test_data.hpp"

namespace {

using epa::plant::EffectKind;

bool named(const epa::diag::Diagnosis& d, EffectKind k) { return std::find(d.effects.begin(), d.effects.end(), k) != d.effects.end(); }

epa::diag::Diagnosis diagnose_hidden(const epa::plant::EffectSet& effects) {
  const epa::diag::ReplayModel nominal{epa::core::paper::model(), {}, 500};
  const auto c = epa::testing::make_case({effects}, 5, 4, 2, 10.0, 0.0);
  return epa::diag::diagnose(nominal, epa::testing::pointers(c.train), epa::testing::pointers(c.heldout), {});
}

TEST(Selection, AGainNominalSomewhereAlongTheStrokeIsThePositionDependenceAlone) {
  epa::plant::EffectSet e;
  e.set(EffectKind::kPositionDependentGain, {0.0, 0.25});  // compressibility: nominal at mid-stroke
  const auto d = diagnose_hidden(e);
  EXPECT_TRUE(named(d, EffectKind::kPositionDependentGain));
  EXPECT_FALSE(named(d, EffectKind::kGainChange));
}

TEST(Selection, AGainOffAlongTheWholeStrokeIsAlsoAGainChange) {
  epa::plant::EffectSet e;
  e.set(EffectKind::kGainChange, {0.6});
  e.set(EffectKind::kPositionDependentGain, {0.0, 0.25});  // 0.6 x (0.7 ... 1.3): below nominal everywhere
  const auto d = diagnose_hidden(e);
  EXPECT_TRUE(named(d, EffectKind::kPositionDependentGain));
  EXPECT_TRUE(named(d, EffectKind::kGainChange));
}

}  // namespace
