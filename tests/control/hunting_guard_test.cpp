// The hunting watch on synthetic readings: a stick-slip limit cycle and a slow smooth one are
// caught within 2 s; a move that overshoots once, a response that swings through the target
// sample by sample and settles, noise at the target and a moving reference are not.
#include "control/hunting_guard.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace epa::control {
namespace {

constexpr double kGuardTs = 0.005;
constexpr double kGuardMmPerV = 50.0;

// Feeds y(t) (mm) for `seconds` at a standing target (mm); returns the time (s) the watch first
// held, or -1.
template <typename Position>
double first_hold_s(double target_mm, double seconds, Position y_mm, HuntingState& s) {
  const HuntingLimits limits = hunting_limits_for(kGuardTs);
  for (int k = 0; k < static_cast<int>(seconds / kGuardTs); ++k)
    if (hunting_step(limits, s, target_mm / kGuardMmPerV, y_mm(k * kGuardTs) / kGuardMmPerV)) return k * kGuardTs;
  return -1.0;
}

// Stuck 6 mm short, a jump past, stuck 6 mm beyond, a jump back, ... 0.75 s a half-cycle, from
// t = 1 s on (arrived short of the target at 0.6 s).
double stick_slip_mm(double t) {
  if (t < 0.6) return 100.0 * t / 0.6 - 6.0 * t / 0.6;
  if (t < 1.0) return 94.0;
  const double phase = std::fmod(t - 1.0, 1.5);
  const double jump_s = 0.05;  // each jump takes 50 ms
  if (phase < jump_s) return 94.0 + 12.0 * phase / jump_s;
  if (phase < 0.75) return 106.0;
  if (phase < 0.75 + jump_s) return 106.0 - 12.0 * (phase - 0.75) / jump_s;
  return 94.0;
}

TEST(HuntingGuard, AStickSlipCycleAboutTheTargetIsHeldWithinTwoSecondsOfItsFirstJump) {
  HuntingState s;
  const double held_s = first_hold_s(100.0, 10.0, stick_slip_mm, s);
  RecordProperty("held_after_first_jump_s", std::to_string(held_s - 1.0));
  ASSERT_GT(held_s, 1.0);
  EXPECT_LE(held_s - 1.0, 2.0);
  EXPECT_TRUE(s.hunting);
}

// Its peaks dwell within the rest band for about 150 ms: rests on alternating sides.
TEST(HuntingGuard, ASlowSmoothOscillationAboutTheTargetIsHeldWithinTwoSeconds) {
  HuntingState s;
  const double held_s = first_hold_s(100.0, 10.0, [](double t) { return 100.0 + 3.0 * std::sin(2.0 * M_PI * 1.2 * t); }, s);
  ASSERT_GT(held_s, 0.0);
  EXPECT_LE(held_s, 2.0);
}

TEST(HuntingGuard, OneOvershootThatComesBackIsNoLimitCycle) {
  HuntingState s;
  // Up to 110 mm past a 100 mm target, rests there, then back to 100.2 mm and stays.
  const auto y = [](double t) { return t < 0.5 ? 220.0 * t : t < 1.5 ? 110.0 : t < 1.7 ? 110.0 - 49.0 * (t - 1.5) : 100.2; };
  EXPECT_LT(first_hold_s(100.0, 10.0, y, s), 0.0);
  // Or back past it once, to rest 3 mm short (the next correction is the law's to make).
  HuntingState s2;
  const auto y2 = [](double t) { return t < 0.5 ? 220.0 * t : t < 1.5 ? 110.0 : t < 1.7 ? 110.0 - 65.0 * (t - 1.5) : 97.0; };
  EXPECT_LT(first_hold_s(100.0, 10.0, y2, s2), 0.0);
}

// As the printed model does under FF-IDZ: through the target and back within samples, then settled
// 0.4 mm off it.
TEST(HuntingGuard, ASwingThroughTheTargetSampleBySampleThatSettlesIsNoLimitCycle) {
  HuntingState s;
  const auto y = [](double t) {
    const int k = static_cast<int>(t / kGuardTs + 0.5);
    static constexpr double kSwing[] = {0.0, 30.0, 19.0, 45.0, 101.0, 80.0, 71.0, 34.0, 62.0, 47.0, 55.0};
    return k < 11 ? kSwing[k] : 50.4;
  };
  EXPECT_LT(first_hold_s(50.0, 5.0, y, s), 0.0);
}

TEST(HuntingGuard, SensorNoiseAtTheTargetIsNoLimitCycle) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);  // mm, as the simulator's default noise
  HuntingState s;
  EXPECT_LT(first_hold_s(100.0, 30.0, [&](double) { return 100.0 + noise(rng); }, s), 0.0);
}

TEST(HuntingGuard, AMovingReferenceIsNeverHeldAndANewTargetEndsAHold) {
  const HuntingLimits limits = hunting_limits_for(kGuardTs);
  HuntingState s;
  for (int k = 0; k < 2000; ++k) {  // a jog's reference, 1 mm a sample ahead, the piston oscillating about it
    const double r_mm = 100.0 + k * 0.05, y_mm = r_mm + 3.0 * std::sin(2.0 * M_PI * 1.2 * k * kGuardTs);
    ASSERT_FALSE(hunting_step(limits, s, r_mm / kGuardMmPerV, y_mm / kGuardMmPerV)) << "sample " << k;
  }
  HuntingState held;
  ASSERT_GT(first_hold_s(100.0, 10.0, stick_slip_mm, held), 0.0);
  EXPECT_TRUE(hunting_step(limits, held, 100.0 / kGuardMmPerV, 100.0 / kGuardMmPerV));   // the same target: held on
  EXPECT_FALSE(hunting_step(limits, held, 150.0 / kGuardMmPerV, 100.0 / kGuardMmPerV));  // the next one: watched afresh
}

}  // namespace
}  // namespace epa::control
