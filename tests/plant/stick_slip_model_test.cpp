// The stick-slip model (plant/stick_slip_model.hpp): each property checked against what the
// equations say a pneumatic axis of that kind does, not against the code's own numbers.
#include <gtest/gtest.h>

#include <cmath>

#include "../support/physics_coast.hpp"
#include "../support/physics_identified_model.hpp"
#include "core/model_file.hpp"
#include "plant/pneumatic_plant.hpp"
#include "plant/stick_slip_model.hpp"
#include "plant/stick_slip_plant.hpp"

namespace epa::plant {
namespace {

constexpr double kTs = 0.005;

StickSlipParams frictionless() {
  StickSlipParams p;
  p.coulomb_mm = 0.0;
  p.static_mm = 0.0;
  return p;
}

// Samples until the piston has moved travel_mm from where it was, holding u; -1 if never within n.
int samples_to_move(StickSlipModel& m, double u, double travel_mm, int n) {
  const double from = m.position_mm();
  for (int k = 1; k <= n; ++k)
    if (std::abs(m.step(u) - from) >= travel_mm) return k;
  return -1;
}

TEST(StickSlipModel, InvalidParametersAreRefusedByName) {
  StickSlipParams p;
  p.static_mm = p.coulomb_mm - 1.0;
  auto m = StickSlipModel::make(p, kTs);
  ASSERT_FALSE(m.has_value());
  EXPECT_NE(m.error().message.find("static_mm"), std::string::npos);
  p = {};
  p.delay_samples = 9;
  EXPECT_NE(StickSlipModel::make(p, kTs).error().message.find("delay_samples"), std::string::npos);
  p = {};
  p.speed_left_mm_s_per_v = NAN;
  EXPECT_NE(StickSlipModel::make(p, kTs).error().message.find("speed_left_mm_s_per_v"), std::string::npos);
  p = {};
  p.spring_rad_s = 1000.0;  // 2.5 ms sub-steps: omega h = 2.5, the explicit steps would blow up
  EXPECT_NE(StickSlipModel::make(p, kTs).error().message.find("too stiff"), std::string::npos);
  EXPECT_TRUE(StickSlipModel::make(p, kTs, 8).has_value());  // 0.625 ms sub-steps hold it
  EXPECT_FALSE(StickSlipModel::make({}, 0.0).has_value());
  EXPECT_FALSE(StickSlipModel::make({}, kTs, 0).has_value());
}

TEST(StickSlipModel, InsideTheFlowDeadZoneNothingMoves) {
  auto m = StickSlipModel::make(frictionless(), kTs);
  ASSERT_TRUE(m.has_value());
  m->reset(250.0);
  for (int k = 0; k < 400; ++k) m->step(k % 2 ? 1.19 : -1.69);  // just inside both break points
  EXPECT_EQ(m->position_mm(), 250.0);
  EXPECT_EQ(m->windup_mm(), 0.0);
}

TEST(StickSlipModel, TheSteadySpeedIsTheFlowsWhateverTheFriction) {
  // z' = w - v: in a steady slide the spring holds the friction and v = w exactly.
  for (double coulomb : {0.0, 3.0, 10.0}) {
    StickSlipParams p;
    p.coulomb_mm = coulomb;
    p.static_mm = coulomb * 1.5;
    p.speed_right_mm_s_per_v = 120.0;
    p.speed_left_mm_s_per_v = 80.0;
    auto m = StickSlipModel::make(p, kTs);
    ASSERT_TRUE(m.has_value());
    for (double u : {2.2, -2.7}) {
      m->reset(250.0);
      for (int k = 0; k < 400; ++k) m->step(u);  // 2 s: the 50 rad/s spring has long settled
      const double expected = u > 0 ? 120.0 * (u - p.break_right_v) : 80.0 * (u - p.break_left_v);
      EXPECT_NEAR(m->speed_mm_s(), expected, 1e-6 * std::abs(expected)) << "coulomb " << coulomb << " u " << u;
    }
  }
}

TEST(StickSlipModel, APistonStaysStuckUntilTheWindUpPassesBreakaway) {
  StickSlipParams p;
  p.coulomb_mm = 4.0;
  p.static_mm = 6.0;
  p.spool_lag_s = 0.0;
  p.delay_samples = 0;
  p.speed_right_mm_s_per_v = 100.0;
  auto m = StickSlipModel::make(p, kTs);
  ASSERT_TRUE(m.has_value());
  m->reset(250.0);
  // 1 V past the break point winds the spring at 100 mm/s: 6 mm takes 60 ms (12 samples).
  const int moved = samples_to_move(*m, p.break_right_v + 1.0, 0.001, 100);
  EXPECT_GE(moved, 12);
  EXPECT_LE(moved, 14);
}

TEST(StickSlipModel, AReversalWaitsForTheSpringToUnwind) {
  // The memory a Hammerstein model lacks: after a move right, the chambers still hold the sliding
  // friction's wind-up, so a left pulse must first unwind it: it starts later than from rest.
  StickSlipParams p;
  p.coulomb_mm = 4.0;
  p.static_mm = 6.0;
  auto fresh = StickSlipModel::make(p, kTs);
  ASSERT_TRUE(fresh.has_value());
  fresh->reset(250.0);
  const int from_rest = samples_to_move(*fresh, -2.7, 0.5, 400);

  auto after = StickSlipModel::make(p, kTs);
  after->reset(250.0);
  for (int k = 0; k < 60; ++k) after->step(2.2);    // a move right
  for (int k = 0; k < 200; ++k) after->step(0.0);   // and a rest: it stops and sticks
  ASSERT_TRUE(after->stuck());
  EXPECT_GT(after->windup_mm(), 0.0);               // the wind-up the stop left
  const int after_right = samples_to_move(*after, -2.7, 0.5, 400);
  ASSERT_GT(from_rest, 0);
  EXPECT_GT(after_right, from_rest + 2);
}

TEST(StickSlipModel, TheDelayLineHoldsTheCommandWholeSamples) {
  for (int delay : {0, 1, 3}) {
    StickSlipParams p = frictionless();
    p.spool_lag_s = 0.0;
    p.delay_samples = delay;
    auto m = StickSlipModel::make(p, kTs);
    ASSERT_TRUE(m.has_value());
    m->reset(0.0);
    int first = -1;
    for (int k = 0; k < 10 && first < 0; ++k)
      if (m->step(3.0) != 0.0) first = k;
    EXPECT_EQ(first, delay) << "delay " << delay;
  }
}

TEST(StickSlipModel, NonFiniteCommandsAreTheCentredValve) {
  auto m = StickSlipModel::make(frictionless(), kTs);
  m->reset(100.0);
  for (int k = 0; k < 100; ++k) m->step(NAN);
  EXPECT_EQ(m->position_mm(), 100.0);
}

TEST(StickSlipModel, ASlowRampStartsThePistonPastTheBreakPointByWhatBreakawayNeeds) {
  // Frictionless, no lag, no delay: at 0.1 V/s the piston has moved 0.5 mm once the integral of
  // the flow, 100 mm/s/V x (u - b)^2 / (2 x 0.1 V/s), reaches 0.5 mm: u - b = 0.032 V (plus the
  // spring's lag behind it). Breakaway friction adds the time to wind it up.
  StickSlipParams p = frictionless();
  p.spool_lag_s = 0.0;
  p.delay_samples = 0;
  p.speed_right_mm_s_per_v = 100.0;
  p.speed_left_mm_s_per_v = 100.0;
  const double right = ramp_start_v(p, kTs, 0.1, 1.0), left = ramp_start_v(p, kTs, 0.1, -1.0);
  EXPECT_GT(right - p.break_right_v, 0.03);
  EXPECT_LT(right - p.break_right_v, 0.06);
  EXPECT_LT(left - p.break_left_v, -0.03);
  p.coulomb_mm = 2.0;
  p.static_mm = 3.0;  // 3 mm of wind-up more: (u - b)^2 = 2 x 0.1 x 3.5 / 100, u - b = 0.084 V
  const double with_friction = ramp_start_v(p, kTs, 0.1, 1.0);
  EXPECT_GT(with_friction - p.break_right_v, 0.07);
  EXPECT_LT(with_friction - p.break_right_v, 0.11);
}

TEST(StickSlipPlant, TheEndStopsHoldThePistonAndTheSensorReadsItWithSeededNoise) {
  StickSlipParams p = frictionless();
  auto plant = StickSlipPlant::make(p, kTs, 50.0, {.initial_position_mm = 480.0, .noise_std_mm = 0.0, .seed = 1, .stroke_mm = 500.0});
  ASSERT_TRUE(plant.has_value()) << plant.error().message;
  for (int k = 0; k < 400; ++k) plant->step(3.0);  // full speed into the far stop
  EXPECT_EQ(plant->position_mm(), 500.0);
  EXPECT_DOUBLE_EQ(plant->measured_v(), 10.0);
  for (int k = 0; k < 400; ++k) plant->step(-3.0);  // and away from it again
  EXPECT_LT(plant->position_mm(), 450.0);

  auto a = StickSlipPlant::make(p, kTs, 50.0, {.initial_position_mm = 250.0, .noise_std_mm = 0.1, .seed = 7, .stroke_mm = 500.0});
  auto b = StickSlipPlant::make(p, kTs, 50.0, {.initial_position_mm = 250.0, .noise_std_mm = 0.1, .seed = 7, .stroke_mm = 500.0});
  double spread = 0.0;
  for (int k = 0; k < 100; ++k) {
    a->step(0.0), b->step(0.0);
    EXPECT_EQ(a->measured_v(), b->measured_v());
    spread = std::max(spread, std::abs(a->measured_v() * 50.0 - 250.0));
  }
  EXPECT_GT(spread, 0.05);  // the noise is there
  EXPECT_LT(spread, 0.6);   // and about 0.1 mm
  EXPECT_FALSE(StickSlipPlant::make(p, kTs, 50.0, {.initial_position_mm = 600.0}).has_value());
}

// The coast pp-traj cuts with, checked against a plant of another form: the physics plant (chambers,
// orifices, Stribeck friction) driven at a steady speed and centred, its coast measured as the law
// reads speed (least-squares slope of 4 readings). The model is the one epa identify fitted to
// open-loop runs of that plant (support/physics_identified_model.hpp).
TEST(StickSlipModel, ItsCoastTimeMatchesThePhysicsPlantsWithinAQuarter) {
  const auto file = core::parse_model_toml(epa::testing::kPhysicsIdentifiedModelToml, "identified");
  ASSERT_TRUE(file.has_value() && file->stick_slip.has_value());
  const StickSlipParams identified = *file->stick_slip;
  for (const double direction : {1.0, -1.0}) {
    SCOPED_TRACE(direction > 0 ? "outwards" : "inwards");
    PneumaticOptions options;
    options.initial_position_mm = direction > 0 ? 100.0 : 400.0;
    auto physics = PneumaticPlant::make(PneumaticParams{}, options);
    ASSERT_TRUE(physics.has_value());
    const double u = direction > 0 ? 2.2 : -2.7;  // about 1 V past each overlap: a steady 100-150 mm/s
    const auto measured = epa::testing::measure_physics_coast(*physics, u, direction, [](int k, double) { return k < 200; });
    const double speed = measured.speed_mm_s, plant_coast_s = measured.coast_s;
    ASSERT_GT(speed, 80.0);
    const double model_coast_s = coast_time_s(identified, kTs, speed);
    EXPECT_GT(plant_coast_s, 0.005);
    EXPECT_NEAR(model_coast_s, plant_coast_s, 0.25 * plant_coast_s) << "speed " << speed << " mm/s";
  }
}

}  // namespace
}  // namespace epa::plant
