#pragma once
// The following error as a user means it: how far the piston is from the motion the law was asked
// to follow. A move with a speed limit, a halt and a jog follow the reference's own profile. A
// move without one hands the law a step, which no axis follows; for it the watch runs the profile
// pp-traj would plan for the same move on the tuning's model (its speeds and accelerations), from
// where the move started. Either motion is then delayed by the lag of a law without feed-forward:
// the paper's laws follow a ramp about a quarter of their 1 s design settling time behind it (60 mm
// at 300 mm/s on the shipped plant), which is their normal motion, not an error.
//
// The piston may be ahead of that motion: the error is its distance from the corridor between the
// expected position and the target, so it grows when the piston lags behind (a blocked or too slow
// axis), stands short (a law that stalls in the dead band) or passes the target (overshoot), and is
// 0 on the way. The position is the mean of the last two readings: a reading that alternates at the
// sampling rate (the paper's printed model does so under FF-IDZ) is not a motion the piston makes.
// Fixed size, allocation-free and noexcept; positions in mm, speeds in mm/s.
#include <algorithm>

#include "control/motion_profile.hpp"

namespace epa::runtime {

inline constexpr double kFollowingLagS = 0.25;  // the law's lag behind the motion it follows, s
// The status bit shows an error that has lasted this long (the fault's time counts from its start):
// the paper's FF-IDZ on its printed model throws readings 200 mm past the target for up to 0.14 s
// when it starts near an end stop, no piston does, and a bit an HMI alarms on must not flicker
// with them.
inline constexpr double kFollowingErrorShownAfterS = 0.2;

class FollowingWatch {
 public:
  explicit FollowingWatch(double Ts) : lag_gain_(Ts / (kFollowingLagS + Ts)) {}

  // A step move from `from_mm` at `speed_mm_s`, expected to go as `expected` plans (mm units);
  // `plan` false: no model to plan with, the reference (the step) is followed.
  void start_step(const control::MotionLimits& expected, bool plan, double from_mm, double speed_mm_s) noexcept {
    own_profile_ = plan;
    expected_mm_ = from_mm;
    if (!plan) return;
    limits_ = expected;
    control::motion_profile_reset(limits_, profile_, from_mm, speed_mm_s);
  }
  // A task that brings its own profile (a speed-limited move, a halt, a jog, a hold), started with
  // the piston at `position_mm`.
  void follow_reference(double position_mm) noexcept {
    own_profile_ = false;
    expected_mm_ = position_mm;
  }

  // One cycle: the error of `position_mm` (mean of the last two readings) against the task's
  // `reference_mm` and `target_mm`.
  double step(double reference_mm, double target_mm, double position_mm) noexcept {
    const double asked = own_profile_ ? control::motion_profile_step(limits_, profile_, target_mm) : reference_mm;
    expected_mm_ += (asked - expected_mm_) * lag_gain_;
    const double lo = std::min(expected_mm_, target_mm), hi = std::max(expected_mm_, target_mm);
    return position_mm < lo ? lo - position_mm : position_mm > hi ? position_mm - hi : 0.0;
  }

 private:
  double lag_gain_;
  bool own_profile_ = false;
  double expected_mm_ = 0.0;
  control::MotionLimits limits_;
  control::MotionProfileState profile_;
};

}  // namespace epa::runtime
