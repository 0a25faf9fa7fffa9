// The model-health monitor's machinery where the model form is right: the plant is the
// commissioned stick-slip model itself, with a term changed mid-run. (On the physics plant, whose
// mechanics the model only approximates, bench/health_drift.cpp measures it.)
#include "diag/model_health.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "../support/physics_identified_model.hpp"
#include "../support/stick_slip_axis.hpp"
#include "core/model_file.hpp"
#include "plant/plant_adapter.hpp"
#include "sim/random_moves.hpp"

namespace epa::diag {
namespace {

constexpr double kHealthTs = testing::StickSlipAxis::kTs;

core::ModelFile health_model_file() {
  auto f = core::parse_model_toml(testing::kPhysicsIdentifiedModelToml, "identified");
  EXPECT_TRUE(f.has_value());
  return *f;
}

// Moves between seeded random targets on the stick-slip model `plant_params`, changed to `changed`
// after change_at moves; each move's run handed to `health`. Returns the move (counted from the
// change) at which `expected` was first named drifting, or -1.
struct HealthRun {
  int named_after = -1;
  double ratio_named = 1.0;
  std::string unit_named;  // of the term named
  int alarms_before_change = 0;
};
HealthRun run_moves(ModelHealth& health, const core::StickSlipParams& plant_params, const core::StickSlipParams& changed, int change_at,
                    int moves, std::optional<plant::EffectKind> expected, std::uint64_t seed) {
  testing::StickSlipAxis axis(health_model_file(), plant_params, seed);
  HealthRun out;
  for (int m = 0; m < moves; ++m) {
    if (m == change_at) axis.change(changed);
    health.add_move(axis.next_move());
    const auto& v = health.verdict();
    const bool alarm = v.state == HealthState::kDrifting || v.state == HealthState::kUnexplained;
    if (m < change_at && alarm) ++out.alarms_before_change;
    if (m >= change_at && out.named_after < 0 && v.state == HealthState::kDrifting && v.effect == expected) {
      out.named_after = m + 1 - change_at;
      out.ratio_named = v.ratio;
      out.unit_named = v.unit;
    }
  }
  return out;
}

TEST(ModelHealth, ItLearnsABaselineFirstThenJudgesAnUnchangedAxisOk) {
  const auto p = *health_model_file().stick_slip;
  auto health = ModelHealth::make(p, kHealthTs, 500.0, {});
  ASSERT_TRUE(health.has_value()) << health.error().message;
  EXPECT_EQ(health->verdict().state, HealthState::kLearning);
  const HealthRun r = run_moves(*health, p, p, 1000, 40, std::nullopt, 1);
  EXPECT_EQ(r.alarms_before_change, 0);
  EXPECT_EQ(health->verdict().state, HealthState::kOk);
  EXPECT_EQ(health->verdict().moves_seen, 40u);
  EXPECT_EQ(health->verdict().estimates.size(), std::size(kMonitoredEffects));
  health->retake_baseline();
  EXPECT_EQ(health->verdict().state, HealthState::kLearning);
  EXPECT_EQ(health->verdict().moves_seen, 0u);
}

TEST(ModelHealth, FrictionDoubledOnTheModelsOwnFormIsNamedWithItsSize) {
  const auto p = *health_model_file().stick_slip;
  auto changed = p;
  changed.static_mm *= 2.0, changed.coulomb_mm *= 2.0;
  auto health = ModelHealth::make(p, kHealthTs, 500.0, {});
  ASSERT_TRUE(health.has_value());
  const HealthRun r = run_moves(*health, p, changed, 28, 60, plant::EffectKind::kStaticFriction, 2);
  EXPECT_EQ(r.alarms_before_change, 0);
  ASSERT_GE(r.named_after, 0) << "friction x2 was never named";
  EXPECT_LE(r.named_after, 20);
  EXPECT_NEAR(r.ratio_named, 2.0, 0.6);
}

TEST(ModelHealth, AFlowGainDownOnTheModelsOwnFormIsNamedDown) {
  const auto p = *health_model_file().stick_slip;
  auto changed = p;
  changed.speed_right_mm_s_per_v *= 0.7, changed.speed_left_mm_s_per_v *= 0.7;
  auto health = ModelHealth::make(p, kHealthTs, 500.0, {});
  ASSERT_TRUE(health.has_value());
  const HealthRun r = run_moves(*health, p, changed, 28, 60, plant::EffectKind::kGainChange, 3);
  ASSERT_GE(r.named_after, 0) << "a flow gain x0.7 was never named";
  EXPECT_LT(r.ratio_named, 0.9);
}

// A lower supply on the model's own form (its air spring softer, the wind-ups longer) is named as
// the gain effect, told as the spring's frequency, down.
TEST(ModelHealth, ASofterAirSpringOnTheModelsOwnFormIsNamedAsTheSupplyDown) {
  const auto p = *health_model_file().stick_slip;
  AxisChange supply;
  supply.terms = {ChangeTerm::kSupply};
  supply.values = {{0.7}};
  const auto changed = apply_change(p, supply);
  auto health = ModelHealth::make(p, kHealthTs, 500.0, {});
  ASSERT_TRUE(health.has_value());
  const HealthRun r = run_moves(*health, p, changed, 28, 60, plant::EffectKind::kGainChange, 4);
  ASSERT_GE(r.named_after, 0) << "an air spring at 0.7 of its frequency was never named";
  EXPECT_EQ(r.unit_named, "rad/s");
  EXPECT_LT(r.ratio_named, 0.85);
}

// On the physics plant (another structure than the model: chambers, orifices, Stribeck friction)
// under pp-traj designed on its identified model, friction doubled after move 32 is named within 20
// moves and stays named to the end, at about its size. The gap of a sticking model is jagged in
// its friction: fitted from "no change" alone, some windows of these seeds read x0.9, and the
// warning went back to ok (seed 3) or to unexplained (seed 2).
TEST(ModelHealthOnThePhysicsPlant, FrictionDoubledIsNamedAndStaysNamed) {
  const auto file = health_model_file();
  const auto law = control::ControllerParams::make(testing::pp_traj_config_on(file));
  ASSERT_TRUE(law.has_value()) << law.error().message;
  for (const std::uint64_t seed : {2u, 3u}) {
    auto plant = plant::make_pneumatic_simulator({}, {.initial_position_mm = 250.0, .noise_std_mm = 0.1, .seed = seed});
    auto health = ModelHealth::make(*file.stick_slip, kHealthTs, 500.0, {});
    ASSERT_TRUE(plant.has_value() && health.has_value());
    sim::RandomMoves moves(**plant, *law, {.seed = seed});
    int named_after = -1;
    for (int m = 0; m < 70; ++m) {
      if (m == 32) {
        auto p = *(*plant)->physics_params();
        p.static_friction_n *= 2.0, p.coulomb_friction_n *= 2.0;
        ASSERT_TRUE(static_cast<bool>((*plant)->set_physics_params(p)));
      }
      auto [run, hunted] = moves.next();
      health->add_move(std::move(run), hunted);
      const auto& v = health->verdict();
      if (m < 32) {
        EXPECT_NE(v.state, HealthState::kDrifting) << "seed " << seed << " move " << m + 1;
      }
      if (m >= 32 && named_after < 0 && v.state == HealthState::kDrifting && v.effect == plant::EffectKind::kStaticFriction) named_after = m + 1 - 32;
    }
    EXPECT_GE(named_after, 1) << "seed " << seed << ": friction x2 was never named";
    EXPECT_LE(named_after, 20) << "seed " << seed;
    const auto& end = health->verdict();
    EXPECT_EQ(end.state, HealthState::kDrifting) << "seed " << seed << " ends " << to_string(end.state);
    EXPECT_EQ(end.effect, plant::EffectKind::kStaticFriction) << "seed " << seed;
    EXPECT_NEAR(end.ratio, 2.0, 0.6) << "seed " << seed;
  }
}

// The judgement's rules, each on estimates made up to sit on one side of it.
EffectEstimate estimate(ChangeTerm term, double reduction, bool beyond_tolerance) {
  EffectEstimate e;
  e.effect = effect_of(term);
  e.term = term;
  e.reduction = reduction;
  e.beyond_tolerance = beyond_tolerance;
  return e;
}

TEST(ModelHealthReading, TheChangeBeyondToleranceThatExplainsMostIsNamed) {
  const std::vector<EffectEstimate> per_term = {estimate(ChangeTerm::kFriction, 0.3, true), estimate(ChangeTerm::kSpoolLag, 0.5, true),
                                                estimate(ChangeTerm::kDeadBand, 0.1, false)};
  const WindowReading r = read_window(per_term, 4.0, 3.0, 2.0, {});
  EXPECT_EQ(r.state, HealthState::kDrifting);
  ASSERT_TRUE(r.named.has_value());
  EXPECT_EQ(*r.named, 1u);
}

// An unchanged axis's window read "spool faster" for a lag that explained a third of its gap while
// friction within its tolerance explained 60 %: the scatter explains it better, so no drift.
TEST(ModelHealthReading, AChangeThatAScatterWithinToleranceExplainsBetterIsNoDrift) {
  const std::vector<EffectEstimate> per_term = {estimate(ChangeTerm::kFriction, 0.6, false), estimate(ChangeTerm::kSpoolLag, 0.33, true)};
  EXPECT_EQ(read_window(per_term, 4.0, 3.0, 2.0, {}).state, HealthState::kOk);
  // The same window with the scatter explaining less than the lag: a drift of the spool.
  const std::vector<EffectEstimate> weaker_scatter = {estimate(ChangeTerm::kFriction, 0.2, false),
                                                      estimate(ChangeTerm::kSpoolLag, 0.33, true)};
  const WindowReading r = read_window(weaker_scatter, 4.0, 3.0, 2.0, {});
  EXPECT_EQ(r.state, HealthState::kDrifting);
  ASSERT_TRUE(r.named.has_value());
  EXPECT_EQ(weaker_scatter[*r.named].term, ChangeTerm::kSpoolLag);
}

TEST(ModelHealthReading, AWindowNoWiderThanTheUnchangedAxisWindowsIsNoDrift) {
  const std::vector<EffectEstimate> per_term = {estimate(ChangeTerm::kFriction, 0.65, true)};
  EXPECT_EQ(read_window(per_term, 3.0, 3.0, 2.0, {}).state, HealthState::kOk);
  EXPECT_EQ(read_window(per_term, 3.1, 3.0, 2.0, {}).state, HealthState::kDrifting);
}

TEST(ModelHealthReading, AChangeThatExplainsTooLittleLeavesAWideGapUnexplained) {
  HealthConfig c;
  const std::vector<EffectEstimate> per_term = {estimate(ChangeTerm::kFriction, c.min_reduction * 0.9, true)};
  EXPECT_EQ(read_window(per_term, 3.9, 3.0, 2.0, c).state, HealthState::kOk);  // within twice the baseline's gap
  const WindowReading wide = read_window(per_term, 4.1, 3.0, 2.0, c);
  EXPECT_EQ(wide.state, HealthState::kUnexplained);
  EXPECT_FALSE(wide.named.has_value());
}

// A drift is judged against the baseline: a lag that grew from a baseline below the commissioned
// one is a slower spool, though it still stands below the commissioned lag.
TEST(ModelHealthWords, ADriftIsToldAsFoundAgainstTheBaselineAndPlacedAgainstTheCommissioned) {
  core::StickSlipParams commissioned;
  commissioned.spool_lag_s = 0.0137;
  auto baseline = commissioned;
  baseline.spool_lag_s = 0.0102;
  auto now = commissioned;
  now.spool_lag_s = 0.0128;
  EXPECT_EQ(drift_words(ChangeTerm::kSpoolLag, baseline, now, commissioned),
            "spool slower: lag 10.2 -> 12.8 ms since the baseline (lag 12.8 ms now, lag 13.7 ms as commissioned)");
  now = baseline;
  now.static_mm = baseline.static_mm * 1.8;
  EXPECT_EQ(drift_words(ChangeTerm::kFriction, baseline, now, commissioned),
            "friction up 80 % since the baseline (breakaway wind-up 14.4 mm now, breakaway wind-up 8 mm as commissioned)");
  now = baseline;
  now.spring_rad_s = 35.0;
  EXPECT_EQ(drift_words(ChangeTerm::kSupply, baseline, now, commissioned),
            "air spring softer: 50 -> 35 rad/s (supply pressure down) since the baseline (air spring 35 rad/s now, air spring 50 rad/s as "
            "commissioned)");
  now = baseline;
  now.delay_samples = 3;
  EXPECT_EQ(drift_words(ChangeTerm::kDeadTime, baseline, now, commissioned),
            "line longer: dead time 1 -> 3 samples since the baseline (dead time 3 samples now, dead time 1 samples as commissioned)");
}

TEST(ModelHealth, ABadConfigurationIsRefusedNamingTheField) {
  const auto p = *health_model_file().stick_slip;
  HealthConfig c;
  c.window_moves = 1;
  const auto h = ModelHealth::make(p, kHealthTs, 500.0, c);
  ASSERT_FALSE(h.has_value());
  EXPECT_NE(h.error().message.find("window_moves"), std::string::npos) << h.error().message;
}

}  // namespace
}  // namespace epa::diag
