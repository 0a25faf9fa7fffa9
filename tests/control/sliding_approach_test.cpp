// pp-traj's arrival while sliding (control/sliding_approach.hpp), on a kinematic piston whose coast
// is known in closed form: its speed follows the commanded path speed through a first-order lag of
// kLagS, so centred at speed v it goes on for v * kLagS and stops (at rest below kRestSpeed).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "control/sliding_approach.hpp"

namespace epa::control {
namespace {

constexpr double kTs = 0.005;
constexpr double kLagS = 0.025;
constexpr double kRestSpeed = 0.05;  // V/s: friction stops it dead below 2.5 mm/s

ApproachLimits limits(double coast_s = kLagS) {
  ApproachLimits l;
  l.coast_s = coast_s;
  l.speed_v_s = 2.4;
  l.length_v = 1.0;
  l.decel_v_s2 = 6.0;
  l.top_speed_pos_v_s = l.top_speed_neg_v_s = 8.0;
  l.accel_v_s2 = 200.0;
  l.retry_band_v = 0.006;
  l.max_retries = 3;
  l.settle_samples = 30;
  l.Ts = kTs;
  return l;
}

struct Trace {
  std::vector<double> y;       // position at each sample
  std::vector<bool> hold;      // valve centred
  std::vector<double> leg_direction;  // of the leg at each sample (0 while not in a leg)
  std::vector<bool> final_leg;        // the leg ends at the target (not a back-off)
};

// Runs the approach against the kinematic piston for `seconds` from rest at y0; `coast_scale` makes
// the piston's real coast differ from the lag (a plant the law's coast gets wrong).
Trace run(const ApproachLimits& l, ApproachState& s, double y0, double r, double seconds, double coast_scale = 1.0) {
  Trace t;
  double y = y0, v = 0.0, last_w = y0;
  const double lag = kLagS * coast_scale;
  for (int k = 0; k < static_cast<int>(seconds / kTs); ++k) {
    const ApproachOutput out = approach_step(l, s, r, y);
    if (out.leg_started) last_w = y;
    double commanded = 0.0;
    if (!out.hold) {
      commanded = out.drive_fraction * (out.w_v - last_w) / kTs;
      last_w = out.w_v;
    }
    v += (commanded - v) * kTs / (lag + kTs);
    if (out.hold && std::abs(v) < kRestSpeed) v = 0.0;
    y += v * kTs;
    t.y.push_back(y);
    t.hold.push_back(out.hold);
    t.leg_direction.push_back(s.phase == ApproachPhase::kLeg ? s.leg_direction : 0.0);
    t.final_leg.push_back(s.phase == ApproachPhase::kLeg && s.final_leg);
  }
  return t;
}

TEST(SlidingApproach, ALongMoveEndsWithinTheBandAtTheFirstApproachAndHolds) {
  const auto l = limits();
  ApproachState s;
  const Trace t = run(l, s, 0.0, 4.0, 4.0);
  EXPECT_NEAR(t.y.back(), 4.0, l.retry_band_v);
  EXPECT_EQ(s.retries, 0);
  EXPECT_EQ(s.phase, ApproachPhase::kHolding);
  EXPECT_TRUE(t.hold.back());
  // It arrived at the approach speed, not at its cruise speed: the cut came from a steady slide.
  EXPECT_NEAR(s.cut_speed_v_s, l.speed_v_s, 0.2 * l.speed_v_s);
  // Never past the target by more than the band.
  EXPECT_LE(*std::max_element(t.y.begin(), t.y.end()), 4.0 + l.retry_band_v);
}

TEST(SlidingApproach, AShortMoveBacksOffFirstSoThatItsFinalApproachIsAWholeApproachLong) {
  const auto l = limits();
  ApproachState s;
  const Trace t = run(l, s, 2.0, 2.5, 4.0);  // 25 mm up, half an approach length
  const double lowest = *std::min_element(t.y.begin(), t.y.end());
  EXPECT_NEAR(lowest, 2.5 - l.length_v, 0.05) << "backed off to one approach length before the target";
  EXPECT_NEAR(t.y.back(), 2.5, l.retry_band_v);
  EXPECT_LE(*std::max_element(t.y.begin(), t.y.end()), 2.5 + l.retry_band_v);
}

TEST(SlidingApproach, AShortMoveNearAnEndBacksOffOnlyToTheEndAndNeverComesFromTheFarSide) {
  auto l = limits();
  l.dead_length_v = 1e6;  // the kinematic piston coasts the same near an end (coast_at_s: no stiffer air spring there)
  ApproachState s;
  const Trace t = run(l, s, 0.3, 0.6, 5.0);  // 15 mm up from 15 mm: a whole approach would start at -20 mm
  EXPECT_NEAR(*std::min_element(t.y.begin(), t.y.end()), l.travel_min_v, 0.05) << "backed off as far as the travel allows";
  EXPECT_LE(*std::max_element(t.y.begin(), t.y.end()), 0.6 + l.retry_band_v) << "passed the target";
  EXPECT_NEAR(t.y.back(), 0.6, l.retry_band_v);
  EXPECT_EQ(s.final_direction, 1.0);
}

TEST(SlidingApproach, APistonBetweenTheTargetAndTheEndGoesStraightIn) {
  auto l = limits();
  l.dead_length_v = 1e6;  // the kinematic piston coasts the same near an end (coast_at_s: no stiffer air spring there)
  ApproachState s;
  const Trace t = run(l, s, 0.0, 0.4, 5.0);  // 20 mm up from the end: no room to back off at all
  EXPECT_GE(*std::min_element(t.y.begin(), t.y.end()), -0.01);
  EXPECT_LE(*std::max_element(t.y.begin(), t.y.end()), 0.4 + l.retry_band_v) << "passed the target";
  EXPECT_NEAR(t.y.back(), 0.4, l.retry_band_v);
}

TEST(SlidingApproach, AStopAfterAShortApproachIsJudgedAgainstTheShortApproachBand) {
  auto l = limits();
  l.dead_length_v = 1e6;
  l.short_approach_band_v = 0.015;  // 3/4 of a 1 mm window
  // The piston coasts 15 % further than the law thinks: each stop lands past the target by more
  // than the band and less than the short approach's band.
  ApproachState short_move;
  const Trace t = run(l, short_move, 0.0, 0.4, 5.0, 1.15);  // 20 mm from the end: a short approach
  const double off_v = std::abs(t.y.back() - 0.4);
  ASSERT_GT(off_v, l.retry_band_v) << "the case does not test the band";
  EXPECT_LE(off_v, l.short_approach_band_v);
  EXPECT_EQ(short_move.retries, 0) << "a retry would be as short: the stop is kept";
  EXPECT_EQ(short_move.phase, ApproachPhase::kHolding);

  // A whole approach with the same error is approached again: its retry can do better.
  ApproachState long_move;
  run(l, long_move, 0.0, 4.0, 8.0, 1.15);
  EXPECT_GE(long_move.retries, 1);
}

TEST(SlidingApproach, AStopAfterAShortApproachTeachesTheCoastNothing) {
  auto l = limits();
  l.dead_length_v = 1e6;
  // From rest at the end, the approach starts with a breakaway: its stop says little of the coast
  // of a steady slide, and learning from it would set the next retry off by as much.
  ApproachState s;
  run(l, s, 0.0, 0.4, 5.0, 1.6);  // 20 mm from the end, the piston coasting 60 % further
  ASSERT_GE(s.retries, 1) << "the case does not stop off the target";
  EXPECT_EQ(s.learned_stops[0], 0);
  EXPECT_EQ(s.learned_offset_s[0], 0.0);

  // A whole approach with the same piston does learn.
  ApproachState whole;
  run(l, whole, 0.0, 4.0, 8.0, 1.6);
  EXPECT_GE(whole.learned_stops[0], 1);
  EXPECT_GT(whole.learned_offset_s[0], 0.0);
}

// The fastest the reference runs in the first `samples` of a move from rest at y0 to r.
double early_reference_speed(const ApproachLimits& l, double y0, double r, int samples) {
  ApproachState s;
  double fastest = 0.0;
  for (int k = 0; k < samples; ++k) fastest = std::max(fastest, std::abs(approach_step(l, s, r, y0).speed_v_s));
  return fastest;
}

TEST(SlidingApproach, AShortApproachSpeedsUpAtItsOwnGentlerRate) {
  auto l = limits();
  l.dead_length_v = 1e6;
  l.short_approach_accel_v_s2 = 14.4;  // the approach speed over 0.2 V
  const int samples = 20;              // 0.1 s: the leg's rate would reach the approach speed in 12 ms
  // From rest at the end, 20 mm to go: a short approach, speeding up at its own rate.
  const double short_speed = early_reference_speed(l, 0.0, 0.4, samples);
  EXPECT_LE(short_speed, l.short_approach_accel_v_s2 * samples * kTs + 1e-9);
  EXPECT_GE(short_speed, l.short_approach_accel_v_s2 * (samples - 2) * kTs);
  // A travel that starts 20 mm up still leaves the piston at 0 mm a whole approach to 60 mm: not short.
  auto raised = l;
  raised.travel_min_v = 0.4;
  EXPECT_GE(early_reference_speed(raised, 0.0, 1.2, samples), l.speed_v_s);
  // A whole approach from mid-stroke, and the same short one without the gentler rate, speed up at the leg's.
  EXPECT_NEAR(early_reference_speed(l, 1.0, 9.0, samples), l.top_speed_pos_v_s, 1e-9);
  l.short_approach_accel_v_s2 = 0.0;
  EXPECT_NEAR(early_reference_speed(l, 0.0, 0.4, samples), l.speed_v_s, 1e-9);
}

TEST(SlidingApproach, ASideAskedForIsTheSideTheNextPlanApproachesFrom) {
  const auto l = limits();
  ApproachState s;
  s.next_direction = 1.0;                    // the move came from below ...
  const Trace t = run(l, s, 4.2, 4.0, 5.0);  // ... and the piston stands 10 mm past its target
  EXPECT_NEAR(*std::min_element(t.y.begin(), t.y.end()), 4.0 - l.length_v, 0.05) << "backed off below the target";
  EXPECT_NEAR(t.y.back(), 4.0, l.retry_band_v);
  EXPECT_EQ(s.final_direction, 1.0);
  EXPECT_EQ(s.next_direction, 0.0) << "asked for once";
}

TEST(SlidingApproach, ASetpointChangedMidMoveContinuesFromThePistonsSpeed) {
  const auto l = limits();
  ApproachState s;
  Trace t = run(l, s, 0.0, 8.0, 0.5);  // cruising upwards
  const double speed = (t.y.back() - t.y[t.y.size() - 2]) / kTs;
  ASSERT_GT(speed, 4.0);
  const double y = t.y.back();
  approach_step(l, s, 6.0, y);  // a new target ahead
  EXPECT_GT(s.path_speed_v_s, 0.8 * speed) << "the new leg starts at the piston's speed, not from rest";
}

TEST(SlidingApproach, ACoastTheLawGetsWrongIsCorrectedByRetriesFromTheSameSide) {
  const auto l = limits(0.5 * kLagS);  // the law expects half the coast: it cuts too late
  ApproachState s;
  const Trace t = run(l, s, 0.0, 4.0, 8.0);
  EXPECT_NEAR(t.y.back(), 4.0, l.retry_band_v);
  EXPECT_GE(s.retries, 1);
  EXPECT_LE(s.retries, l.max_retries);
  EXPECT_GT(s.learned_offset_s[0], 0.0) << "the coast it cuts with grew towards the piston's";
  EXPECT_GT(s.leg_coast_s, 0.5 * kLagS);
  // Every approach to the target was upward: a retry backs off and comes from the same side.
  std::size_t approach_samples = 0;
  for (std::size_t k = 0; k < t.y.size(); ++k) {
    if (t.final_leg[k]) {
      EXPECT_EQ(t.leg_direction[k], 1.0);
      ++approach_samples;
    }
  }
  EXPECT_GT(approach_samples, 0u);
}

TEST(SlidingApproach, AfterMaxRetriesItHoldsWhereverItStoppedAndStartsNoFurtherLeg) {
  auto l = limits();
  l.retry_band_v = 1e-7;  // unreachable
  l.max_retries = 2;
  ApproachState s;
  const Trace t = run(l, s, 0.0, 4.0, 10.0, 1.3);
  EXPECT_EQ(s.retries, 2);
  EXPECT_EQ(s.phase, ApproachPhase::kHolding);
  // Held for the last 2 s, still.
  const std::size_t last2 = t.y.size() - static_cast<std::size_t>(2.0 / kTs);
  for (std::size_t k = last2; k < t.y.size(); ++k) {
    EXPECT_TRUE(t.hold[k]);
    EXPECT_EQ(t.y[k], t.y.back());
  }
}

TEST(SlidingApproach, APistonPushedAwayWhileHoldingIsApproachedAgainAndANewSetpointReplans) {
  const auto l = limits();
  ApproachState s;
  run(l, s, 0.0, 4.0, 4.0);
  ASSERT_EQ(s.phase, ApproachPhase::kHolding);
  // Pushed 2 bands away: still held.
  Trace t = run(l, s, 4.0 + 2.0 * l.retry_band_v, 4.0, 0.2);
  EXPECT_TRUE(t.hold.back());
  // Pushed 10 bands away: approached again, and it ends within the band.
  t = run(l, s, 4.0 + 10.0 * l.retry_band_v, 4.0, 4.0);
  EXPECT_FALSE(std::all_of(t.hold.begin(), t.hold.end(), [](bool h) { return h; }));
  EXPECT_NEAR(t.y.back(), 4.0, l.retry_band_v);
  // A new setpoint: planned from where the piston is.
  t = run(l, s, t.y.back(), 1.0, 5.0);
  EXPECT_NEAR(t.y.back(), 1.0, l.retry_band_v);
  EXPECT_EQ(s.planned_r_v, 1.0);
}

TEST(SlidingApproach, ASetpointWithinTheBandStartsNoMove) {
  const auto l = limits();
  ApproachState s;
  const Trace t = run(l, s, 3.0, 3.0 + 0.5 * l.retry_band_v, 1.0);
  EXPECT_TRUE(std::all_of(t.hold.begin(), t.hold.end(), [](bool h) { return h; }));
  EXPECT_EQ(t.y.back(), 3.0);
}

// The air spring that brakes the piston is stiffest near an end, where one chamber is short: the
// coast the law assumes is coast_s at mid-stroke and shorter towards either end, the same at
// mirrored positions, and the flatter the longer the chambers' dead volume.
TEST(SlidingApproach, TheCoastShortensTowardsEitherEndAsTheAirSpringStiffens) {
  auto l = limits();
  l.dead_length_v = 0.25;
  EXPECT_DOUBLE_EQ(coast_at_s(l, 5.0), l.coast_s);
  double previous = coast_at_s(l, 5.0);
  for (double x = 4.5; x >= 0.0; x -= 0.5) {
    const double coast = coast_at_s(l, x);
    EXPECT_LT(coast, previous) << "at " << x << " V";
    EXPECT_NEAR(coast, coast_at_s(l, 10.0 - x), 1e-12) << "mirrored";
    previous = coast;
  }
  // At the end one chamber is its dead volume alone: stiffness 1/0.25 + 1/10.25 against
  // 2/5.25 at mid-stroke, omega sqrt(10.76) times higher.
  EXPECT_NEAR(coast_at_s(l, 0.0) / l.coast_s, std::sqrt((2.0 / 5.25) / (1.0 / 0.25 + 1.0 / 10.25)), 1e-12);
  auto longer = l;
  longer.dead_length_v = 2.0;
  EXPECT_GT(coast_at_s(longer, 0.5), coast_at_s(l, 0.5));
  EXPECT_EQ(coast_at_s(l, -1.0), coast_at_s(l, 0.0)) << "outside the stroke: its end";
}

// A stop the law's coast gets wrong teaches an offset, not a factor: a coast the model misses by a
// delay it did not see is off by that delay at every position, so what one stop taught holds for
// the next target elsewhere along the stroke.
TEST(SlidingApproach, WhatAStopTaughtIsAnOffsetThatTheNextMoveElsewhereUses) {
  auto l = limits(0.5 * kLagS);  // the law expects half the coast
  ApproachState s;
  run(l, s, 5.0, 8.0, 8.0);
  ASSERT_GT(s.learned_offset_s[0], 0.0);
  const double learned = s.learned_offset_s[0];
  approach_step(l, s, 2.0, s.readings[0]);  // a move down: that direction has learned nothing
  EXPECT_EQ(s.learned_offset_s[1], 0.0);
  EXPECT_EQ(s.leg_coast_s, coast_at_s(l, 2.0)) << "its cut adds nothing to the coast";
  ApproachState up = s;
  up.phase = ApproachPhase::kIdle;
  approach_step(l, up, 9.5, 1.0);  // up again, far along the stroke
  EXPECT_NEAR(up.leg_coast_s, coast_at_s(l, 9.5) + learned, 1e-12);
}

// A stop scatters about what the coast predicts; once four stops have taught a direction, one more
// moves its offset by a quarter of what it asks for, not all of it, so retries do not chase the
// scatter. The first stop, with nothing learned yet, is taken whole.
TEST(SlidingApproach, AfterFourStopsOneMoreMovesTheOffsetByAQuarterOfItsError) {
  auto l = limits(0.5 * kLagS);  // the law expects half the coast: every stop asks for more
  l.max_retries = 0;             // one approach per move: one stop, one lesson
  ApproachState fresh;
  run(l, fresh, 0.0, 4.0, 3.0);
  ASSERT_EQ(fresh.learned_stops[0], 1);
  const double first_lesson_s = fresh.learned_offset_s[0];
  ASSERT_GT(first_lesson_s, 0.0);

  ApproachState taught;
  taught.learned_stops = {4, 0};  // four stops taught it an offset of 0 upwards
  run(l, taught, 0.0, 4.0, 3.0);
  EXPECT_NEAR(taught.learned_offset_s[0], 0.25 * first_lesson_s, 1e-9);
  EXPECT_EQ(taught.learned_stops[0], 5);
}

}  // namespace
}  // namespace epa::control
