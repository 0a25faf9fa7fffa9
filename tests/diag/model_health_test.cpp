// The model-health monitor's machinery where the model form is right: the plant is the
// commissioned stick-slip model itself, with a term changed mid-run. (On the physics plant, whose
// mechanics the model only approximates, bench/health_drift.cpp measures it.)
#include "diag/model_health.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../support/physics_identified_model.hpp"
#include "../support/pp_traj_on_model.hpp"
#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/model_file.hpp"
#include "core/random.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::diag {
namespace {

constexpr double kHealthTs = 0.005;

core::ModelFile health_model_file() {
  auto f = core::parse_model_toml(testing::kPhysicsIdentifiedModelToml, "identified");
  EXPECT_TRUE(f.has_value());
  return *f;
}

control::ControllerParams health_law(const core::ModelFile& f) { return *control::ControllerParams::make(testing::pp_traj_config_on(f)); }

// Moves between seeded random targets on the stick-slip model `plant_params`, changed to `changed`
// after change_at moves; each move's run handed to `health`. Returns the move (counted from the
// change) at which `expected` was first named drifting, or -1.
struct HealthRun {
  int named_after = -1;
  double ratio_named = 1.0;
  int alarms_before_change = 0;
};
HealthRun run_moves(ModelHealth& health, const core::StickSlipParams& plant_params, const core::StickSlipParams& changed, int change_at,
                    int moves, std::optional<plant::EffectKind> expected, std::uint64_t seed) {
  const auto file = health_model_file();
  const auto law = health_law(file);
  auto plant = *plant::StickSlipModel::make(plant_params, kHealthTs);
  plant.reset(250.0);
  core::Random noise(seed);
  core::Random targets(seed * 31 + 7);
  control::ControllerState state;
  double target_mm = 250.0;
  HealthRun out;
  for (int m = 0; m < moves; ++m) {
    if (m == change_at) {
      const double y = plant.position_mm();
      plant = *plant::StickSlipModel::make(changed, kHealthTs);
      plant.reset(y);
    }
    const double size = 20.0 + 150.0 * targets.uniform();
    target_mm = std::clamp(target_mm + (target_mm > 250.0 ? -size : size), 30.0, 470.0);
    control::controller_new_move(state);
    core::Run run;
    run.Ts = kHealthTs;
    double y_mm = plant.position_mm();
    for (int k = 0; k < 500; ++k) {  // 2.5 s
      const double reading_mm = y_mm + 0.05 * noise.normal();
      const auto u = control::controller_step(law, state, target_mm / 50.0, reading_mm / 50.0);
      run.t_s.push_back(k * kHealthTs);
      run.r_mm.push_back(target_mm);
      run.y_mm.push_back(reading_mm);
      run.u_V.push_back(u.valve_v);
      y_mm = std::clamp(plant.step(u.valve_v), 0.0, 500.0);
    }
    health.add_move(std::move(run));
    const auto& v = health.verdict();
    const bool alarm = v.state == HealthState::kDrifting || v.state == HealthState::kUnexplained;
    if (m < change_at && alarm) ++out.alarms_before_change;
    if (m >= change_at && out.named_after < 0 && v.state == HealthState::kDrifting && v.effect == expected) {
      out.named_after = m + 1 - change_at;
      out.ratio_named = v.ratio;
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
  EXPECT_EQ(health->verdict().estimates.size(), std::size(kAxisChanges));
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
