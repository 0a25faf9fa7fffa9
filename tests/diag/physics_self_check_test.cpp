// The self-check on the physics plant: a valve-side effect hidden around the pneumatic cylinder
// (which the nominal ARX model never describes exactly: friction, compressibility, choked flow),
// diagnosed against the model identified from the same plant without it. What the diagnosis
// names on the effect-free plant is the plant's own structure; the hidden effect must be named
// on top of it, and the gap it added must mostly go. The horizon is 40 samples (0.2 s): over the
// default 10, an 8-sample delay hides in the plant's own mismatch. Under the sanitizers
// (tests/support/sanitizer_run.hpp) the delay alone: the lag takes the same paths on top of the
// same plant (and DiagnoseCli.* has diagnose() name it there).
#include <gtest/gtest.h>

#include <algorithm>

#include "diag/selection.hpp"
#include "../support/sanitizer_run.hpp"
#include "diag_test_data.hpp"
#include "physics_case.hpp"

namespace {

using epa::plant::EffectKind;

struct PhysicsOutcome {
  std::vector<std::string> named;
  std::vector<std::string> confusable;
  double before_mm = 0, after_mm = 0;
  bool unexplained = false;
};

const epa::core::HammersteinModel& nominal() {
  static const auto m = [] {
    std::vector<epa::core::Run> runs;
    for (std::uint64_t s = 0; s < 4; ++s) runs.push_back(epa::testing::make_physics_run({}, s % 2 == 0, 15.0, 900 + s));
    return epa::testing::identify_physics_nominal(runs);
  }();
  return m;
}

PhysicsOutcome diagnose_physics(const epa::plant::EffectSet& hidden, std::uint64_t seed) {
  std::vector<epa::core::Run> train, heldout;
  for (std::uint64_t i = 0; i < 6; ++i)
    (i < 4 ? train : heldout).push_back(epa::testing::make_physics_run(hidden, i % 2 == 0, 10.0, seed * 100 + i));
  epa::diag::DiagnosisOptions options;
  options.horizon = 40;
  const auto d = epa::diag::diagnose({nominal(), {}, 500.0}, epa::testing::pointers(train), epa::testing::pointers(heldout), options);
  PhysicsOutcome o{{}, {}, d.baseline_gap_mm, d.final_gap_mm, d.unexplained};
  for (auto k : d.effects) o.named.emplace_back(epa::plant::to_string(k));
  for (const auto& [a, b] : d.confusable) o.confusable.emplace_back(epa::plant::to_string(a)), o.confusable.emplace_back(epa::plant::to_string(b));
  std::cout << "hidden " << hidden.describe() << ": named";
  for (const auto& n : o.named) std::cout << " " << n;
  std::cout << "; gap " << o.before_mm << " -> " << o.after_mm << " mm\n";
  return o;
}

bool names(const PhysicsOutcome& o, const std::string& effect) {
  return std::find(o.named.begin(), o.named.end(), effect) != o.named.end() ||
         std::find(o.confusable.begin(), o.confusable.end(), effect) != o.confusable.end();
}

TEST(PhysicsSelfCheck, AHiddenValveEffectIsNamedOnTopOfThePlantsOwnStructure) {
  const auto baseline = diagnose_physics({}, 1);
  for (const auto kind : {EffectKind::kInputDelay, EffectKind::kValveLag}) {
    if (kind == EffectKind::kValveLag && epa::test::sanitizer_run()) continue;
    epa::plant::EffectSet hidden;
    if (kind == EffectKind::kInputDelay) hidden.set(kind, {8});
    else hidden.set(kind, {0.04});
    const auto o = diagnose_physics(hidden, 1);
    const std::string truth(epa::plant::to_string(kind));
    EXPECT_TRUE(names(o, truth)) << truth << " not named";
    EXPECT_FALSE(names(baseline, truth)) << truth << " blamed on the plant without it";
    // The plant's own structure leaves a gap no library effect removes (the baseline's); the part
    // the hidden effect added must mostly go.
    const double added_mm = o.before_mm - baseline.before_mm;
    EXPECT_GT(added_mm, 0.0) << truth;
    EXPECT_GT(o.before_mm - o.after_mm, 0.5 * added_mm) << truth;
  }
}

}  // namespace
