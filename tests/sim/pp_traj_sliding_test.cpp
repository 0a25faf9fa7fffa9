// pp-traj arriving while sliding (control/sliding_approach.hpp) on the physics plant, a cylinder
// with stiction whose form is not the law's model: issue 17's physics limits. The law gets what
// commissioning gives it, a model file as `epa identify` wrote it from open-loop runs of the default
// physics plant (epa excite --plant physics --seed 1,2,3 --duration 30; epa identify ex1 ex2
// --validate ex3, 2026-11-27): the Hammerstein model for its feed-forward, and the stick-slip model
// that describes the axis for its coast.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "control/paper_controller.hpp"
#include "core/model_file.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"
#include "plant/stick_slip_model.hpp"
#include "sim/closed_loop.hpp"

namespace epa::sim {
namespace {

constexpr const char* kIdentifiedModel = R"(schema = "epa-model/1"
Ts = 0.005
mm_per_volt = 50.0
source = 'epa identify: na=4 nb=1 nk=1 from ex1.csv, ex2.csv; validation free-run fit 54.86 %; stick-slip model: validation free-run fit 96.70 %'
axis_model = "stick-slip"

[arx]
A = [1.0, -1.089166190990138, -0.32295729667453776, 0.1172131221902894, 0.29491036547438637]
B = [0.0, 0.0024317052709731135]

[dead_zone]
m_r = 1.2198620103542206
m_l = 1.0707
b_r = 1.345
b_l = -1.8193712892465246

[stick_slip]
break_right_v = 1.176969689128404
break_left_v = -1.683703334845168
speed_right_mm_s_per_v = 112.57081259160479
speed_left_mm_s_per_v = 109.02932094462616
spring_rad_s = 59.015440817565505
damping_ratio = 0.20904450655623621
coulomb_mm = 5.66702578402857
static_mm = 5.768196811811399
spool_lag_s = 0.013662491569187415
delay_samples = 1
)";

core::ModelFile identified() {
  auto f = core::parse_model_toml(kIdentifiedModel, "identified");
  EXPECT_TRUE(f.has_value()) << (f ? "" : f.error().message);
  return *f;
}

control::ControllerParams pp_traj_for(const core::ModelFile& f) {
  auto c = control::paper_controller_config(control::ControllerKind::kPpTraj);
  c.A = f.model.A;
  c.B = f.model.B;
  c.dead_zone = f.model.dead_zone;
  c.trajectory.coast_s = plant::sliding_arrival_coast_s(f, 50.0 * c.trajectory.approach_speed_v_s);
  auto p = control::ControllerParams::make(c);
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
  const double coast = plant::sliding_arrival_coast_s(f, 120.0);
  EXPECT_GT(coast, 0.005);
  EXPECT_LT(coast, 0.1);
  f.axis_model = core::AxisModel::kHammerstein;
  EXPECT_EQ(plant::sliding_arrival_coast_s(f, 120.0), 0.0);
}

TEST(PpTrajSliding, OnThePhysicsPlantEveryMoveEndsWithinAThirdOfAMillimetreWithoutOvershoot) {
  const auto params = pp_traj_for(identified());
  for (double from : {100.0, 250.0, 400.0})
    for (double step : {25.0, 50.0, 100.0, -25.0, -50.0, -100.0}) {
      SCOPED_TRACE("from " + std::to_string(from) + " mm, step " + std::to_string(step) + " mm");
      const StepRun r = physics_move(params, from, step);
      const double final_error = std::abs(r.run.y_mm.back() - (from + step));
      EXPECT_LE(final_error, 0.3);
      ASSERT_TRUE(r.metrics.overshoot_pct.has_value());
      EXPECT_LE(*r.metrics.overshoot_pct / 100.0 * std::abs(step), 0.5) << "overshoot in mm";
      EXPECT_EQ(valve_sign_changes_in_last(r, 1.0), 0u) << "held still at the end";
      EXPECT_EQ(r.faults, 0u);
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

// A halt's braking, a jog or a move with a speed limit hands the law a reference that moves sample
// after sample (runtime/axis_motion.hpp): it is followed, and once it stands the piston, still
// sliding towards it, is cut at its predicted stop once (no retry after a moving reference, so that
// a halt never sets off a back-off): within a first approach's millimetre.
TEST(PpTrajSliding, AMovingReferenceIsFollowedAndTheArrivalTakesOverWhereItStops) {
  const auto params = pp_traj_for(identified());
  auto plant = plant::make_pneumatic_simulator(plant::PneumaticParams{}, {.initial_position_mm = 150.0});
  ASSERT_TRUE(plant.has_value());
  control::ControllerState state;
  double worst_lag_mm = 0.0, r_mm = 150.0;
  for (int k = 0; k < 1000; ++k) {  // 5 s: a ramp at 100 mm/s for 1.5 s (to 299.5 mm), then 3.5 s standing
    if (k < 300) r_mm = 150.0 + 100.0 * 0.005 * k;
    const double y_mm = (*plant)->measured_v() * 50.0;
    if (k >= 100 && k < 300) worst_lag_mm = std::max(worst_lag_mm, std::abs(r_mm - y_mm));
    const auto out = control::controller_step(params, state, r_mm / 50.0, (*plant)->measured_v());
    ASSERT_FALSE(out.fault);
    (*plant)->step(out.valve_v);
  }
  EXPECT_LT(worst_lag_mm, 15.0) << "followed the ramp";
  EXPECT_NEAR((*plant)->measured_v() * 50.0, r_mm, 1.0) << "and arrived where it stopped";
  EXPECT_EQ(state.trajectory.approach.phase, control::ApproachPhase::kHolding);
}

// A halt: the reference brakes to a stop point and stands there. The piston (lagging the reference
// by 6-10 mm) is cut or let coast and held where it stops, near that point, and no new move starts
// (no back-off of 50 mm and approach again after a halt).
TEST(PpTrajSliding, AfterAHaltsBrakingThePistonIsHeldWhereItStopsWithoutANewMove) {
  const auto params = pp_traj_for(identified());
  auto plant = plant::make_pneumatic_simulator(plant::PneumaticParams{}, {.initial_position_mm = 150.0});
  ASSERT_TRUE(plant.has_value());
  control::ControllerState state;
  double r_mm = 150.0, speed_mm_s = 0.0;
  double furthest_after_mm = 0.0, stop_mm = 0.0;
  for (int k = 0; k < 1000; ++k) {  // up to 150 mm/s, then braking at 1500 mm/s^2, then standing
    if (k < 200) speed_mm_s = std::min(150.0, speed_mm_s + 1500.0 * 0.005);
    else speed_mm_s = std::max(0.0, speed_mm_s - 1500.0 * 0.005);
    r_mm += speed_mm_s * 0.005;
    const double y_mm = (*plant)->measured_v() * 50.0;
    if (k == 230) stop_mm = r_mm;  // the reference stands from here on
    if (k > 230) furthest_after_mm = std::max(furthest_after_mm, std::abs(y_mm - stop_mm));
    const auto out = control::controller_step(params, state, r_mm / 50.0, (*plant)->measured_v());
    ASSERT_FALSE(out.fault);
    (*plant)->step(out.valve_v);
  }
  ASSERT_EQ(r_mm, stop_mm);
  EXPECT_LT(furthest_after_mm, 15.0) << "no back-off after the halt (it is 50 mm)";
  EXPECT_EQ(state.trajectory.approach.phase, control::ApproachPhase::kHolding);
}

TEST(PpTrajSliding, TheSameLawWithoutTheCoastHuntsOnThisPlant) {
  // The reason the sliding arrival exists: pp-traj's integrator, correcting from rest, hunts here.
  auto f = identified();
  f.axis_model = core::AxisModel::kHammerstein;
  const auto params = pp_traj_for(f);
  int ended_off = 0;
  for (double step : {25.0, 50.0, -25.0, -50.0})
    if (std::abs(physics_move(params, 250.0, step).run.y_mm.back() - (250.0 + step)) > 0.3) ++ended_off;
  EXPECT_GE(ended_off, 2);
}

}  // namespace
}  // namespace epa::sim
