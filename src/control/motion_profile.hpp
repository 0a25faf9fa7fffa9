#pragma once
// An online, jerk-limited motion profile towards a target that may change at any sample: a
// velocity- and acceleration-limited path (trapezoid, or triangle for short moves) that brakes just
// in time, followed by a moving average over `smoothing_samples`, which bounds the jerk to
// accel / (smoothing_samples Ts) and turns the trapezoid into an S-curve. A target change mid-move
// starts from the current position and velocity, so the profile never jumps. Fixed storage, no
// allocation; positions in sensor volts.
#include <array>
#include <cstddef>

namespace epa::control {

inline constexpr std::size_t kMaxSmoothingSamples = 64;

struct MotionLimits {
  double speed_pos_v_s = 10.0;  // top speed towards larger positions, V/s (sensor volts)
  double speed_neg_v_s = 10.0;  // towards smaller positions
  double accel_v_s2 = 100.0;    // acceleration and braking at most, V/s^2
  // Short moves accelerate less: accel = min(accel_v_s2, accel_per_distance |move|), 1/s^2, so a
  // move of any length takes at least 2 / sqrt(accel_per_distance). A plant whose response leads
  // its input's acceleration (the paper's B, docs/paper.md) would otherwise overshoot a short move.
  // 0: accel_v_s2 always.
  double accel_per_distance = 0.0;
  std::size_t smoothing_samples = 1;  // 1..kMaxSmoothingSamples; 1: no smoothing (trapezoid)
  double Ts = 0.005;            // sample period, s
};

struct MotionProfileState {
  bool started = false;
  double position_v = 0.0;  // the unsmoothed path
  double speed_v_s = 0.0;
  double target_v = 0.0;    // the target the acceleration below was chosen for
  double accel_v_s2 = 0.0;  // this move's acceleration
  std::array<double, kMaxSmoothingSamples> window{};  // last smoothing_samples path positions
  std::size_t next = 0;                                // ring index of the oldest
};

// Starts the profile at `position_v` moving at `speed_v_s` (clamped to the limits; 0: at rest),
// the smoothing window filled as if it had been moving so for a while.
void motion_profile_reset(const MotionLimits& limits, MotionProfileState& state, double position_v, double speed_v_s = 0.0) noexcept;

// Advances one sample towards `target_v` and returns the smoothed position w(k).
double motion_profile_step(const MotionLimits& limits, MotionProfileState& state, double target_v) noexcept;

// True once the path is at the target at rest and the smoothing window has caught up with it.
bool motion_profile_arrived(const MotionLimits& limits, const MotionProfileState& state, double target_v) noexcept;

}  // namespace epa::control
