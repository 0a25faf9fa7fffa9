// pp-traj on the paper's printed model, judged against the paper's FF-IDZ measured in the same
// run (pp-traj's acceptance), with sensor noise, and on plants its model gets wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "plant/plant_adapter.hpp"
#include "sim/closed_loop.hpp"
#include "sim/model_perturbation.hpp"
#include "paper_steps.hpp"

namespace epa::sim {
namespace {

using control::ControllerKind;

using testing::kPaperStepsMm;
using testing::sign_changes_in_last_10s;

control::ControllerParams params_of(ControllerKind kind) {
  auto p = control::ControllerParams::make(control::paper_controller_config(kind));
  EXPECT_TRUE(p.has_value()) << (p ? "" : p.error().message);
  return *p;
}

StepRun step_on(ControllerKind kind, double step_mm, const ModelPerturbation& plant = {}, const ValveLineOptions& line = {},
            double noise_mm = 0.0) {
  auto simulator = plant::make_hammerstein_simulator(perturbed(core::paper::model(), plant), {.noise_std_mm = noise_mm, .seed = 7});
  EXPECT_TRUE(simulator.has_value());
  auto r = simulate_step_on(**simulator, 50.0, params_of(kind), {.step_mm = step_mm, .duration_s = 20.0, .noise_std_mm = noise_mm}, line);
  EXPECT_TRUE(r.has_value());
  EXPECT_EQ(r->faults, 0u);
  return *r;
}

TEST(PpTraj, BeatsFfIdzOnThePrintedModelOnEveryCriterionOfIssue17) {
  for (double step : kPaperStepsMm) {
    SCOPED_TRACE("step " + std::to_string(step) + " mm");
    const StepRun ff = step_on(ControllerKind::kPpFfidz, step);
    const StepRun traj = step_on(ControllerKind::kPpTraj, step);
    const auto& m = traj.metrics;
    ASSERT_TRUE(m.rise_s && m.settling_s && m.overshoot_pct && ff.metrics.rise_s && ff.metrics.settling_s);
    EXPECT_LE(*m.overshoot_pct, 0.5);
    EXPECT_LE(*m.settling_s, 0.6 * *ff.metrics.settling_s);
    EXPECT_LE(*m.settling_s, 0.7);
    EXPECT_LE(m.ess_mm, 0.15);
    EXPECT_EQ(sign_changes_in_last_10s(traj), 0u);
    const double rise_limit_s = step <= 50 ? 0.85 * *ff.metrics.rise_s : step == 100 ? 0.30 : 0.40;
    EXPECT_LE(*m.rise_s, rise_limit_s);
  }
}

TEST(PpTraj, WithSensorNoiseItStaysWithinTheNoiseAndHoldsTheValve) {
  for (double step : kPaperStepsMm) {
    const StepRun traj = step_on(ControllerKind::kPpTraj, step, {}, {}, 0.1);
    EXPECT_LE(traj.metrics.ess_mm, 0.2) << step;
    EXPECT_LE(sign_changes_in_last_10s(traj), 2u) << step;
  }
}

// The robustness cases (docs/paper.md, "Robustness"): the plant differs, the controller keeps the printed model.
struct RobustnessCase {
  const char* name;
  ModelPerturbation plant;
  ValveLineOptions line;
};
const RobustnessCase kRobustnessCases[] = {{"gain x0.8", {.gain_factor = 0.8}, {}},
                                           {"gain x1.2", {.gain_factor = 1.2}, {}},
                                           {"dead band 0.1 V wider", {.dead_band_widening_v = 0.1}, {}},
                                           {"dead band 0.1 V narrower", {.dead_band_widening_v = -0.1}, {}},
                                           {"20 ms valve lag", {}, {.lag_s = 0.02}},
                                           {"1 sample delay", {}, {.delay_samples = 1}}};

// The robustness cases. Asserted in all of them: no divergence, no chatter, e_ss within
// 0.15 mm, settled within 3 s (10 s with the delay). The overshoot limit (30 %) is asserted in the
// next test, for every case but the 20 ms valve lag, whose short moves still exceed it (README).
TEST(PpTraj, OnPlantsItsModelGetsWrongItHoldsTheTargetWithoutChatterAndSettlesInTime) {
  for (const auto& c : kRobustnessCases) {
    for (double step : kPaperStepsMm) {
      SCOPED_TRACE(std::string(c.name) + ", step " + std::to_string(step) + " mm");
      const StepRun traj = step_on(ControllerKind::kPpTraj, step, c.plant, c.line);
      EXPECT_NEAR(traj.metrics.final_mm, step, 0.15);
      EXPECT_LE(traj.metrics.ess_mm, 0.15);
      EXPECT_LE(sign_changes_in_last_10s(traj), 2u);
      ASSERT_TRUE(traj.metrics.settling_s.has_value());
      EXPECT_LE(*traj.metrics.settling_s, c.line.delay_samples > 0 ? 10.0 : 3.0);
    }
  }
}

// Overshoot within the 30 % limit on plants whose gain, dead band or timing the model gets
// wrong. Short moves were the hard ones: the creeping inverse dead zone used to take over at
// arrival in one sample, which stepped the drive of such a plant, and the printed B answers a
// step of its drive with a spike (gain x1.2 at 25 mm: 30.6 %, dead band 0.1 V narrower: 40.2 %).
TEST(PpTraj, OnPlantsItsModelGetsWrongShortAndLongMovesOvershootAtMost30Percent) {
  for (const auto& c : kRobustnessCases) {
    for (double step : kPaperStepsMm) {
      SCOPED_TRACE(std::string(c.name) + ", step " + std::to_string(step) + " mm");
      const StepRun traj = step_on(ControllerKind::kPpTraj, step, c.plant, c.line);
      ASSERT_TRUE(traj.metrics.overshoot_pct.has_value());
      EXPECT_LE(*traj.metrics.overshoot_pct, 30.0);
    }
  }
}

// Once arrived, the creeping inverse's margin grows from 0 (NG-IDZ, the command used while
// moving) to creep_margin_v over creep_blend_s; a new move starts again from NG-IDZ.
TEST(PpTraj, TheCreepingMarginBlendsInAfterArrivalAndEndsWithTheNextMove) {
  auto config = control::paper_controller_config(ControllerKind::kPpTraj);
  config.trajectory.creep_margin_v = 0.2;
  config.trajectory.creep_blend_s = 0.05;  // 10 samples at 5 ms
  auto p = control::ControllerParams::make(config);
  ASSERT_TRUE(p.has_value());
  control::TrajectoryState s;
  const double y_v = 2.0;
  control::trajectory_reset(p->trajectory(), s, y_v);
  double last = 0.0;
  for (int k = 1; k <= 15; ++k) {
    const auto out = control::trajectory_step(p->trajectory(), s, y_v, y_v, 0);  // at rest on the target
    ASSERT_TRUE(out.arrived);
    EXPECT_NEAR(out.creep_margin_v, std::min(0.2, 0.02 * k), 1e-12) << k;
    EXPECT_GE(out.creep_margin_v, last);
    last = out.creep_margin_v;
  }
  const auto moving = control::trajectory_step(p->trajectory(), s, y_v + 1.0, y_v, 0);  // a new setpoint 50 mm on
  EXPECT_FALSE(moving.arrived);
  EXPECT_EQ(moving.creep_margin_v, 0.0);

  config.trajectory.creep_blend_s = -1.0;
  auto bad = control::ControllerParams::make(config);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("creep_blend_s"), std::string::npos) << bad.error().message;
}

TEST(PpTraj, ANonFiniteReadingGivesTheSafeCommandAndKeepsTheState) {
  const auto p = params_of(ControllerKind::kPpTraj);
  control::ControllerState state;
  control::controller_step(p, state, 1.0, 0.0);
  const auto before = state.trajectory.profile.position_v;
  const auto out = control::controller_step(p, state, 1.0, std::numeric_limits<double>::quiet_NaN());
  EXPECT_TRUE(out.fault);
  EXPECT_EQ(out.valve_v, p.safe_valve_v());
  EXPECT_EQ(state.trajectory.profile.position_v, before);
}

TEST(PpTraj, AModelThatDoesNotIntegrateOrABadParameterIsRefusedByName) {
  auto config = control::paper_controller_config(ControllerKind::kPpTraj);
  config.A = core::Polynomial({1.0, -0.5});  // a stable first-order model: no integrator
  auto p = control::ControllerParams::make(config);
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("integrates"), std::string::npos) << p.error().message;

  config = control::paper_controller_config(ControllerKind::kPpTraj);
  config.trajectory.speed_fraction = 1.5;
  p = control::ControllerParams::make(config);
  ASSERT_FALSE(p);
  EXPECT_NE(p.error().message.find("speed_fraction"), std::string::npos) << p.error().message;

  // The sliding arrival's parameters are checked when it is on (coast_s > 0).
  for (const double dead_length_v : {0.0, -0.5, std::nan("")}) {
    config = control::paper_controller_config(ControllerKind::kPpTraj);
    config.trajectory.coast_s = 0.024;
    config.trajectory.coast_dead_length_v = dead_length_v;
    p = control::ControllerParams::make(config);
    ASSERT_FALSE(p) << dead_length_v;
    EXPECT_NE(p.error().message.find("coast_dead_length"), std::string::npos) << p.error().message;
  }

  config = control::paper_controller_config(ControllerKind::kPpFfidz);  // the other laws do not need the model
  config.A = core::Polynomial({1.0, -0.5});
  EXPECT_TRUE(control::ControllerParams::make(config));
}

}  // namespace
}  // namespace epa::sim
