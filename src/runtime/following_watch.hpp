#pragma once
// The following error as a user means it: how far the piston is from the motion the law was asked
// to follow. A move with a speed limit, a halt and a jog follow the reference's own profile. A
// move without one hands the law a step, which no axis follows; for it the watch runs the profile
// pp-traj would plan for the same move on the tuning's model (its speeds and accelerations), from
// where the move started. The piston may be ahead of that motion: the error is its distance from
// the corridor between the expected position and the target, so it grows when the piston lags
// behind (a blocked or too slow axis) or passes the target (overshoot), and is 0 on the way.
//
// The position is the mean of the last two readings: a reading that alternates at the sampling
// rate (the paper's printed model does so under FF-IDZ) is not a motion the piston makes.
// Fixed size, allocation-free and noexcept; positions in mm, speeds in mm/s.
#include <algorithm>

#include "control/motion_profile.hpp"

namespace epa::runtime {

class FollowingWatch {
 public:
  // A step move from `from_mm` at `speed_mm_s` to its target, expected to go as `expected` plans
  // (mm units); `plan` false: no model to plan with, the reference (the step) is followed.
  void start_step(const control::MotionLimits& expected, bool plan, double from_mm, double speed_mm_s) noexcept {
    own_profile_ = plan;
    if (!plan) return;
    limits_ = expected;
    control::motion_profile_reset(limits_, profile_, from_mm, speed_mm_s);
  }
  // A task that brings its own profile (a speed-limited move, a halt, a jog, a hold).
  void follow_reference() noexcept { own_profile_ = false; }

  // One cycle: the error of `position_mm` (mean of the last two readings) against the task's
  // `reference_mm` and `target_mm`.
  double step(double reference_mm, double target_mm, double position_mm) noexcept {
    const double expected = own_profile_ ? control::motion_profile_step(limits_, profile_, target_mm) : reference_mm;
    const double lo = std::min(expected, target_mm), hi = std::max(expected, target_mm);
    return position_mm < lo ? lo - position_mm : position_mm > hi ? position_mm - hi : 0.0;
  }

 private:
  bool own_profile_ = false;
  control::MotionLimits limits_;
  control::MotionProfileState profile_;
};

}  // namespace epa::runtime
