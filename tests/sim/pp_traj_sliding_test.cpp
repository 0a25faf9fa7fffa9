// pp-traj arriving while sliding (control/sliding_approach.hpp) on the physics plant, a cylinder
// with stiction whose form is not the law's model, held to pp-traj's limits there. The law gets what
// commissioning gives it, a model file `epa identify` wrote from open-loop runs of that plant
// (support/physics_identified_model.hpp): the Hammerstein model for its feed-forward, and the
// stick-slip model that describes the axis for its coast.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "../support/physics_coast.hpp"
#include "../support/physics_identified_model.hpp"
#include "../support/pp_traj_on_model.hpp"
#include "control/paper_controller.hpp"
#include "control/sliding_approach.hpp"
#include "core/model_file.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"
#include "plant/pneumatic_plant.hpp"
#include "plant/stick_slip_model.hpp"
#include "sim/closed_loop.hpp"
#include "sim/valve_line.hpp"

namespace epa::sim {
namespace {

core::ModelFile identified() {
  auto f = core::parse_model_toml(epa::testing::kPhysicsIdentifiedModelToml, "identified");
  EXPECT_TRUE(f.has_value()) << (f ? "" : f.error().message);
  return *f;
}

control::ControllerParams pp_traj_for(const core::ModelFile& f) {
  auto p = control::ControllerParams::make(epa::testing::pp_traj_config_on(f));
  EXPECT_TRUE(p.has_value()) << (p ? "" : p.error().message);
  return *p;
}

StepRun physics_move(const control::ControllerParams& params, double from_mm, double step_mm, std::size_t delay_samples = 0) {
  auto plant = plant::make_pneumatic_simulator(plant::PneumaticParams{}, {.initial_position_mm = from_mm});
  EXPECT_TRUE(plant.has_value());
  auto r = simulate_step_on(**plant, 50.0, params, {.step_mm = step_mm, .initial_mm = from_mm, .duration_s = 5.0},
                            {.delay_samples = delay_samples});
  EXPECT_TRUE(r.has_value());
  return *r;
}

TEST(PpTrajSliding, TheCoastComesFromTheStickSlipModelOnlyWhenItDescribesTheAxis) {
  auto f = identified();
  const auto coast = plant::sliding_arrival_coast_s(f, 120.0);
  ASSERT_TRUE(coast.has_value());
  EXPECT_GT(*coast, 0.005);
  EXPECT_LT(*coast, 0.1);
  f.axis_model = core::AxisModel::kHammerstein;
  const auto off = plant::sliding_arrival_coast_s(f, 120.0);
  ASSERT_TRUE(off.has_value());
  EXPECT_EQ(*off, 0.0);
}

// The physics plant's coast, centred after a steady slide at ~100-150 mm/s through x_mm: its run-up
// starts 150 mm before x.
double physics_coast_s(double x_mm, double direction) {
  plant::PneumaticOptions options;
  options.initial_position_mm = std::clamp(x_mm - direction * 150.0, 0.0, 500.0);
  auto physics = plant::PneumaticPlant::make(plant::PneumaticParams{}, options);
  EXPECT_TRUE(physics.has_value());
  const double u = direction > 0 ? 2.2 : -2.75;  // about 1 V past each overlap
  const auto measured = epa::testing::measure_physics_coast(
      *physics, u, direction, [&](int k, double y_mm) { return k < 2000 && direction * (y_mm - x_mm) < 0.0; });
  EXPECT_GT(measured.speed_mm_s, 90.0);
  return measured.coast_s;
}

// The law's coast along the stroke (control::coast_at_s, 1/omega of an air spring of two chambers
// with dead volumes) against a plant of another form: the physics plant's chambers, orifices and
// Stribeck friction, its coast measured after slides that reach x steadily (at least 150 mm of
// run-up). Given the plant's coast at mid-stroke and its dead volumes as lengths, the form follows
// it within 6 % from 25 mm to 475 mm; a coast taken as the same everywhere misses by a third at
// 25 mm.
TEST(PpTrajSliding, TheCoastAlongTheStrokeFollowsThePhysicsPlant) {
  const plant::PneumaticParams physics;
  const double area_a_mm2 = std::numbers::pi / 4.0 * physics.bore_mm * physics.bore_mm;
  const double area_b_mm2 = area_a_mm2 - std::numbers::pi / 4.0 * physics.rod_mm * physics.rod_mm;
  control::ApproachLimits l;
  l.dead_length_v = 0.5 * (1e3 * physics.dead_volume_a_cm3 / area_a_mm2 + 1e3 * physics.dead_volume_b_cm3 / area_b_mm2) / 50.0;
  for (const double direction : {1.0, -1.0}) {
    SCOPED_TRACE(direction > 0 ? "outwards" : "inwards");
    l.coast_s = physics_coast_s(250.0, direction);
    for (const double x_mm : {25.0, 50.0, 100.0, 150.0, 350.0, 400.0, 450.0, 475.0}) {
      if (direction * (x_mm - 250.0) < 0.0) continue;  // a slide needs its 150 mm of run-up within the stroke
      SCOPED_TRACE("at " + std::to_string(x_mm) + " mm");
      const double plant_coast_s = physics_coast_s(x_mm, direction);
      EXPECT_NEAR(control::coast_at_s(l, x_mm / 50.0), plant_coast_s, 0.06 * plant_coast_s);
    }
  }
  EXPECT_LT(physics_coast_s(25.0, -1.0), 0.67 * physics_coast_s(250.0, -1.0)) << "a coast the same everywhere would miss";
}

// pp-traj's limits on the physics plant, on the 18 moves of bench/pp_traj_tables.sh: each from a
// fresh law, so nothing is learned from an earlier move, and every first approach must land within
// the band.
TEST(PpTrajSliding, OnThePhysicsPlantEveryMoveSettlesWithinASecondWithinAThirdOfAMillimetreWithoutOvershoot) {
  const auto params = pp_traj_for(identified());
  for (double from : {100.0, 250.0, 400.0})
    for (double step : {25.0, 50.0, 100.0, -25.0, -50.0, -100.0}) {
      SCOPED_TRACE("from " + std::to_string(from) + " mm, step " + std::to_string(step) + " mm");
      const StepRun r = physics_move(params, from, step);
      const double final_error = std::abs(r.run.y_mm.back() - (from + step));
      EXPECT_LE(final_error, 0.3);
      ASSERT_TRUE(r.metrics.settling_s.has_value());
      EXPECT_LE(*r.metrics.settling_s, 1.0);
      ASSERT_TRUE(r.metrics.overshoot_pct.has_value());
      EXPECT_LE(*r.metrics.overshoot_pct / 100.0 * std::abs(step), 0.5) << "overshoot in mm";
      EXPECT_EQ(valve_sign_changes_in_last(r, 1.0), 0u) << "held still at the end";
      EXPECT_EQ(r.faults, 0u);
    }
}

// Moves from an end stop to targets nearer than one approach length: the approach is as short as
// the target is near, and starts from rest at the end. A gripper or a part may stand past the
// target, so none passes it by more than the in-position window (1 mm); each ends within it.
TEST(PpTrajSliding, AShortMoveFromAnEndStopDoesNotPassItsTarget) {
  auto config = epa::testing::pp_traj_config_on(identified());
  config.trajectory.in_position_window_v = 1.0 / 50.0;
  auto params = control::ControllerParams::make(config);
  ASSERT_TRUE(params.has_value()) << params.error().message;
  for (double from : {0.0, 500.0})
    for (double size : {10.0, 15.0, 20.0, 25.0}) {
      const double step = from == 0.0 ? size : -size, target = from + step;
      SCOPED_TRACE("from " + std::to_string(from) + " mm, step " + std::to_string(step) + " mm");
      const StepRun r = physics_move(*params, from, step);
      double passed_mm = 0.0;
      for (const double y : r.run.y_mm) passed_mm = std::max(passed_mm, (y - target) * (step > 0 ? 1.0 : -1.0));
      EXPECT_LE(passed_mm, 1.0);
      EXPECT_LE(std::abs(r.run.y_mm.back() - target), 1.0);
    }
}

TEST(PpTrajSliding, WithTwoSamplesOfDelayTheModelDoesNotKnowItStillEndsWithinTheBand) {
  const auto params = pp_traj_for(identified());
  for (double from : {100.0, 400.0})
    for (double step : {25.0, -50.0, 100.0}) {
      SCOPED_TRACE("from " + std::to_string(from) + " mm, step " + std::to_string(step) + " mm");
      const StepRun r = physics_move(params, from, step, 2);
      EXPECT_LE(std::abs(r.run.y_mm.back() - (from + step)), 0.3);
      EXPECT_EQ(valve_sign_changes_in_last(r, 1.0), 0u);
    }
}

// In the appliance the law's state lives from move to move, and what the stops taught stays: with
// 2 samples of delay the model does not know, the first approach each way goes about 1.2 mm too
// far and is approached again; the offset learned from it carries to the moves after, which then
// land in the band at their first approach, along the whole stroke.
TEST(PpTrajSliding, WithADelayTheModelDoesNotKnowWhatTheFirstMovesTaughtCarriesToTheNext) {
  const auto params = pp_traj_for(identified());
  auto plant = plant::make_pneumatic_simulator(plant::PneumaticParams{}, {.initial_position_mm = 250.0});
  ASSERT_TRUE(plant.has_value());
  control::ControllerState state;
  sim::ValveLine line({.delay_samples = 2}, 0.005);
  const std::vector<double> targets_mm = {300, 200, 350, 150, 250, 320, 180, 400, 100, 250, 275, 225};
  for (std::size_t move = 0; move < targets_mm.size(); ++move) {
    const double target_mm = targets_mm[move];
    SCOPED_TRACE("move " + std::to_string(move) + " to " + std::to_string(target_mm) + " mm");
    const double from_mm = (*plant)->measured_v() * 50.0;
    double past_mm = 0.0;
    for (int k = 0; k < 800; ++k) {  // 4 s
      const auto out = control::controller_step(params, state, target_mm / 50.0, (*plant)->measured_v());
      (*plant)->step(line.pass(out.valve_v));
      past_mm = std::max(past_mm, (target_mm > from_mm ? 1.0 : -1.0) * ((*plant)->measured_v() * 50.0 - target_mm));
    }
    EXPECT_LE(std::abs((*plant)->measured_v() * 50.0 - target_mm), 0.3);
    const int retries = state.trajectory.approach.retries;
    if (move == 0) {
      EXPECT_GE(retries, 1) << "the model's coast misses the delay: the first approach needs a retry";
    }
    if (move >= 3) {
      EXPECT_EQ(retries, 0) << "learned";
      EXPECT_LE(past_mm, 0.3) << "no approach went past the band";
    }
  }
}

// The law on the physics plant from rest at from_mm, following reference_mm sample by sample: the
// measured positions and the law's state at the end.
struct ReferenceRun {
  std::vector<double> y_mm;
  control::ControllerState state;
};
ReferenceRun follow(const control::ControllerParams& params, double from_mm, const std::vector<double>& reference_mm,
                    const plant::PneumaticParams& rig = {}) {
  ReferenceRun run;
  auto plant = plant::make_pneumatic_simulator(rig, {.initial_position_mm = from_mm});
  EXPECT_TRUE(plant.has_value());
  for (const double r_mm : reference_mm) {
    run.y_mm.push_back((*plant)->measured_v() * 50.0);
    const auto out = control::controller_step(params, run.state, r_mm / 50.0, (*plant)->measured_v());
    EXPECT_FALSE(out.fault);
    (*plant)->step(out.valve_v);
  }
  run.y_mm.push_back((*plant)->measured_v() * 50.0);
  return run;
}

// A halt's braking, a jog or a move with a speed limit hands the law a reference that moves sample
// after sample (runtime/axis_motion.hpp): it is followed, and once it stands the piston, still
// sliding towards it, is cut at its predicted stop once (no retry after a moving reference, so that
// a halt never sets off a back-off): within a first approach's millimetre.
TEST(PpTrajSliding, AMovingReferenceIsFollowedAndTheArrivalTakesOverWhereItStops) {
  std::vector<double> reference_mm(1000);  // 5 s: a ramp at 100 mm/s for 1.5 s (to 299.5 mm), then 3.5 s standing
  for (int k = 0; k < 1000; ++k) reference_mm[k] = 150.0 + 100.0 * 0.005 * std::min(k, 299);
  const ReferenceRun run = follow(pp_traj_for(identified()), 150.0, reference_mm);
  double worst_lag_mm = 0.0;
  for (int k = 100; k < 300; ++k) worst_lag_mm = std::max(worst_lag_mm, std::abs(reference_mm[k] - run.y_mm[k]));
  EXPECT_LT(worst_lag_mm, 15.0) << "followed the ramp";
  EXPECT_NEAR(run.y_mm.back(), reference_mm.back(), 1.0) << "and arrived where it stopped";
  EXPECT_EQ(run.state.trajectory.approach.phase, control::ApproachPhase::kHolding);
}

// A halt: the reference brakes to a stop point and stands there. The piston (lagging the reference
// by 6-10 mm) is cut or let coast and held where it stops, near that point, and no new move starts
// (no back-off of 50 mm and approach again after a halt).
TEST(PpTrajSliding, AfterAHaltsBrakingThePistonIsHeldWhereItStopsWithoutANewMove) {
  std::vector<double> reference_mm(1000);  // up to 150 mm/s, then braking at 1500 mm/s^2, then standing
  double r_mm = 150.0, speed_mm_s = 0.0;
  for (int k = 0; k < 1000; ++k) {
    speed_mm_s = k < 200 ? std::min(150.0, speed_mm_s + 1500.0 * 0.005) : std::max(0.0, speed_mm_s - 1500.0 * 0.005);
    r_mm += speed_mm_s * 0.005;
    reference_mm[k] = r_mm;
  }
  const double stop_mm = reference_mm[230];  // the reference stands from here on
  ASSERT_EQ(reference_mm.back(), stop_mm);
  const ReferenceRun run = follow(pp_traj_for(identified()), 150.0, reference_mm);
  double furthest_after_mm = 0.0;
  for (std::size_t k = 231; k < run.y_mm.size(); ++k) furthest_after_mm = std::max(furthest_after_mm, std::abs(run.y_mm[k] - stop_mm));
  EXPECT_LT(furthest_after_mm, 15.0) << "no back-off after the halt (it is 50 mm)";
  EXPECT_EQ(run.state.trajectory.approach.phase, control::ApproachPhase::kHolding);
}

TEST(PpTrajSliding, TheSameLawWithoutTheCoastHuntsThenFallsBackToArrivingWhileSliding) {
  // pp-traj's integrator, correcting from rest, hunts here; once the hunting watch sees the cycle
  // the law arrives while sliding, from the side the move came from, with a guessed coast.
  auto f = identified();
  f.axis_model = core::AxisModel::kHammerstein;
  const auto params = pp_traj_for(f);
  ASSERT_FALSE(params.trajectory().sliding_approach);
  for (double step : {25.0, 50.0, -25.0, -50.0}) {
    auto plant = plant::make_pneumatic_simulator(plant::PneumaticParams{}, {.initial_position_mm = 250.0});
    ASSERT_TRUE(plant.has_value());
    const auto r = simulate_step_on(**plant, 50.0, params, {.step_mm = step, .initial_mm = 250.0, .duration_s = 12.0});
    ASSERT_TRUE(r.has_value());
    EXPECT_NEAR(r->run.y_mm.back(), 250.0 + step, 0.3) << "step " << step;
    EXPECT_GE(r->valve_sign_changes, 2u) << "step " << step << ": it was expected to hunt before it fell back";
    EXPECT_EQ(valve_sign_changes_in_last(*r, 6.0), 0u) << "step " << step << ": held still at the end";
  }
}

// The shipped law (pp-traj on the paper's model, no stick-slip model) on a rig with stiction whose
// valve is not the default's (the commissioning test's: orifices x0.8, overlap +0.2 V), commanded
// like an HMI, one law over ten moves of 25-200 mm held 5 s each. It hunts on its first move and
// falls back to arriving while sliding; from then on a stop within the in-position window is kept.
// With the fallback judging its stops at the set's 0.3 mm instead, a stop 0.78 mm short backed off
// 50 mm and approached again three times, and the HMI read a move 49.7 mm from its target at 5 s.
TEST(PpTrajSliding, TheHuntingFallbackKeepsAStopWithinTheInPositionWindow) {
  plant::PneumaticParams rig;
  rig.orifice_area_mm2 = 3.2, rig.overlap_pos_v = 1.4, rig.overlap_neg_v = -1.5;
  constexpr double kWindowMm = 1.0;
  constexpr std::size_t kMoveSamples = 1000;  // 5 s
  auto config = control::paper_controller_config(control::ControllerKind::kPpTraj);
  config.trajectory.in_position_window_v = kWindowMm / 50.0;
  const auto params = control::ControllerParams::make(config);
  ASSERT_TRUE(params.has_value()) << params.error().message;
  const std::vector<double> targets_mm = {225.0, 275.0, 175.0, 275.0, 125.0, 325.0, 250.0, 50.0, 250.0, 450.0};
  std::vector<double> reference_mm;
  for (const double t : targets_mm) reference_mm.insert(reference_mm.end(), kMoveSamples, t);
  const ReferenceRun run = follow(*params, 250.0, reference_mm, rig);
  ASSERT_TRUE(run.state.trajectory.sliding_fallback) << "it was expected to hunt on the first move and fall back";
  for (std::size_t m = 0; m < targets_mm.size(); ++m) {
    const double target_mm = targets_mm[m];
    const double end_mm = run.y_mm[(m + 1) * kMoveSamples];  // the reading as the next move starts
    EXPECT_LE(std::abs(end_mm - target_mm), kWindowMm) << "move to " << target_mm << " mm ends at " << end_mm << " mm";
    if (m == 0) continue;  // the hunt before the fallback
    bool kept = false;  // the piston has stood within the window (10 samples alike)
    double worst_after_kept_mm = 0.0;
    int still = 0;
    for (std::size_t k = m * kMoveSamples + 1; k <= (m + 1) * kMoveSamples; ++k) {
      still = std::abs(run.y_mm[k] - run.y_mm[k - 1]) < 0.05 ? still + 1 : 0;
      kept = kept || (still >= 10 && std::abs(run.y_mm[k] - target_mm) <= kWindowMm);
      if (kept) worst_after_kept_mm = std::max(worst_after_kept_mm, std::abs(run.y_mm[k] - target_mm));
    }
    EXPECT_LE(worst_after_kept_mm, kWindowMm) << "move to " << target_mm << " mm: left the window after standing in it";
  }
}

}  // namespace
}  // namespace epa::sim
