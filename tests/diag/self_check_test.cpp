// The self-check on withheld effects: data made with each effect hidden in the simulator (the
// paper's model slightly perturbed, seeded noise, closed- and open-loop runs), diagnosed without
// being told; the diagnosis must name the hidden effect, blame nothing on effect-free data, say
// "unexplained" for a disturbance outside the library, and shrink the held-out gap. The confusion
// matrix goes to build/.../artifacts/diag_confusion.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/format.hpp"
#include "diag/chance_threshold.hpp"
#include "diag/selection.hpp"
#include "../support/sanitizer_run.hpp"
#include "diag_test_data.hpp"

namespace {

using epa::plant::EffectKind;

// Three seeds; one under the sanitizers (tests/support/sanitizer_run.hpp): every case takes the
// same paths whatever its seed, and three took about 400 s there.
const int kSeeds = epa::test::sanitizer_run() ? 1 : 3;

// Under the sanitizers the effect-free cases and the hidden effects no other test of that run has
// diagnose() name; the other four (40 % of this test's time) are named there by Selection.*
// (gain_change, position_dependent_gain), DiagnoseCli.* (valve_lag) and PhysicsSelfCheck
// (input_delay), and every case fits all eight effects in its first round.
bool in_this_run(EffectKind kind) {
  if (!epa::test::sanitizer_run()) return true;
  return kind == EffectKind::kDeadzoneShift || kind == EffectKind::kStaticFriction || kind == EffectKind::kFlowSaturation ||
         kind == EffectKind::kSensorQuantization;
}

struct Outcome {
  std::string truth, named;  // named: the effect, "none" or "unexplained"
  std::vector<std::string> all_named;
  double before_mm = 0, after_mm = 0;
  std::vector<epa::diag::CandidateScore> candidates;  // every candidate's held-out reduction and threshold
};

std::string label(const epa::diag::Diagnosis& d, const std::string& truth) {
  if (d.effects.empty()) return d.unexplained ? "unexplained" : "none";
  for (auto k : d.effects)
    if (epa::plant::to_string(k) == truth) return truth;
  for (const auto& [a, b] : d.confusable)
    if (epa::plant::to_string(b) == truth) return truth;  // named as a confusable pair
  return std::string(epa::plant::to_string(d.effects.front()));
}

std::vector<Outcome> run_all() {
  std::vector<Outcome> out;
  const epa::diag::ReplayModel nominal{epa::core::paper::model(), {}, 500.0};
  for (int seed = 1; seed <= kSeeds; ++seed) {
    for (int which = -2; which < static_cast<int>(epa::plant::kEffectCount); ++which) {
      epa::testing::Hidden h;
      std::string truth = "none";
      if (which == -1) h.periodic_mm = 1.5, truth = "outside the library";
      if (which >= 0) {
        const auto kind = epa::plant::kAllEffects[static_cast<std::size_t>(which)];
        if (!in_this_run(kind)) continue;
        h.effects = epa::testing::typical_effect(kind), truth = std::string(epa::plant::to_string(kind));
      }
      const auto c = epa::testing::make_case(h, static_cast<std::uint64_t>(seed));
      const auto d = epa::diag::diagnose(nominal, epa::testing::pointers(c.train), epa::testing::pointers(c.heldout), {});
      Outcome o{truth, label(d, truth), {}, d.baseline_gap_mm, d.final_gap_mm, d.candidates};
      for (auto k : d.effects) o.all_named.emplace_back(epa::plant::to_string(k));
      out.push_back(o);
    }
  }
  return out;
}

const std::vector<Outcome>& outcomes() {
  static const std::vector<Outcome> o = run_all();
  return o;
}

TEST(SelfCheck, WritesTheConfusionMatrix) {
  std::vector<std::string> rows = {"none", "outside the library"}, cols;
  for (auto k : epa::plant::kAllEffects) rows.emplace_back(epa::plant::to_string(k));
  cols = rows;
  cols.erase(cols.begin() + 1);
  cols.push_back("unexplained");
  std::map<std::pair<std::string, std::string>, int> m;
  int co_blamed = 0, effect_free = 0, false_blame = 0;
  for (const auto& o : outcomes()) {
    ++m[{o.truth, o.named}];
    if (o.truth == "none" || o.truth == "outside the library") effect_free += o.truth == "none", false_blame += o.truth == "none" && !o.all_named.empty();
    else co_blamed += o.all_named.size() > 1;
  }
  std::ostringstream md;
  md << "Hidden effect (rows) vs what `epa diagnose` named (columns), " << kSeeds << " seeds each; "
     << "each case: 4 training + 2 held-out runs of 10 s, closed- and open-loop, 0.1 mm sensor noise, "
     << "the paper's model perturbed (steady gain +-3 %, break points +-0.02 V).\n\n| hidden \\ named |";
  for (const auto& c : cols) md << " " << c << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < cols.size(); ++i) md << "---|";
  md << "\n";
  for (const auto& r : rows) {
    md << "| " << r << " |";
    for (const auto& c : cols) md << " " << (m.count({r, c}) ? std::to_string(m[{r, c}]) : "") << " |";
    md << "\n";
  }
  // The chance distribution: what fitting each effect gains on effect-free data.
  std::map<std::string, double> chance_max;
  for (const auto& o : outcomes())
    if (o.truth == "none")
      for (const auto& c : o.candidates) {
        auto& largest = chance_max[std::string(epa::plant::to_string(c.kind))];
        largest = std::max(largest, c.reduction_vs_refit_pct);
      }
  md << "\nChance: the largest held-out reduction (%, against the re-fitted model) that fitting each effect gave on "
     << "the effect-free cases, against its acceptance threshold:";
  for (const auto& [k, v] : chance_max) md << " " << k << " " << epa::core::format_number(v) << " (" << epa::core::format_number(epa::diag::chance_threshold_pct(epa::plant::parse_effect(k).value())) << ")";
  md << "\nFalse blame on effect-free data: " << false_blame << " of " << effect_free << " cases. Cases where a second "
     << "effect was named beside the hidden one: " << co_blamed << ".\n";
  const auto dir = std::filesystem::path(EPA_ARTIFACTS_DIR);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "diag_confusion.md") << md.str();
  std::cout << md.str();
}

TEST(SelfCheck, BlamesNothingOnEffectFreeData) {
  for (const auto& o : outcomes())
    if (o.truth == "none") { EXPECT_TRUE(o.all_named.empty()) << o.named; }
}

// The thresholds in chance_threshold.hpp are what chance gives, with room: on effect-free data
// (the perturbed model's own rounding, noise) no candidate comes within 80 % of its threshold.
TEST(SelfCheck, ChanceThresholdsStayAboveWhatFittingGivesOnEffectFreeData) {
  for (const auto& o : outcomes()) {
    if (o.truth != "none") continue;
    ASSERT_FALSE(o.candidates.empty());
    for (const auto& c : o.candidates)
      EXPECT_LT(c.reduction_vs_refit_pct, 0.8 * epa::diag::chance_threshold_pct(c.kind)) << epa::plant::to_string(c.kind);
  }
}

TEST(SelfCheck, SaysUnexplainedForADisturbanceOutsideTheLibrary) {
  for (const auto& o : outcomes())
    if (o.truth == "outside the library") { EXPECT_EQ(o.named, "unexplained"); }
}

TEST(SelfCheck, NamesTheHiddenEffectAndShrinksTheHeldOutGap) {
  for (const auto& o : outcomes()) {
    if (o.truth == "none" || o.truth == "outside the library") continue;
    EXPECT_EQ(o.named, o.truth);
    // A replay cannot predict which way a reading rounds: quantisation raises the floor the gap
    // can reach instead of shrinking it. It is named because its rounding accounts for the gap.
    if (o.truth == "sensor_quantization") continue;
    EXPECT_LT(o.after_mm, 0.5 * o.before_mm) << o.truth;
  }
}

}  // namespace
