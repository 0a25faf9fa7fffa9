#include "control/motion_profile.hpp"

#include <algorithm>
#include <cmath>

namespace epa::control {

void motion_profile_reset(const MotionLimits& l, MotionProfileState& s, double position_v, double speed_v_s) noexcept {
  s.started = true;
  s.position_v = position_v;
  s.speed_v_s = std::isfinite(speed_v_s) ? std::clamp(speed_v_s, -l.speed_neg_v_s, l.speed_pos_v_s) : 0.0;
  s.target_v = position_v;
  s.accel_v_s2 = l.accel_v_s2;
  // The window's oldest first: what the path was at the same speed, centred on position_v so the
  // smoothed output starts where the piston is.
  const auto n = l.smoothing_samples;
  for (std::size_t i = 0; i < n; ++i)
    s.window[i] = position_v + s.speed_v_s * l.Ts * (static_cast<double>(i) - 0.5 * static_cast<double>(n - 1));
  s.position_v = s.window[n - 1];
  s.next = 0;
}

double motion_profile_step(const MotionLimits& l, MotionProfileState& s, double target_v) noexcept {
  const double d = target_v - s.position_v;
  if (target_v != s.target_v) {  // a new move: its acceleration, enough to stop in time if moving
    s.target_v = target_v;
    double a = l.accel_per_distance > 0.0 ? std::min(l.accel_v_s2, l.accel_per_distance * std::abs(d)) : l.accel_v_s2;
    if (std::abs(d) > 0.0) a = std::max(a, std::min(l.accel_v_s2, s.speed_v_s * s.speed_v_s / (2.0 * std::abs(d))));
    s.accel_v_s2 = a > 0.0 ? a : l.accel_v_s2;
  }
  const double dv = s.accel_v_s2 * l.Ts;  // speed change allowed in one sample
  // The speed from which braking by dv per sample covers exactly |d|: n (n + 1) / 2 dv Ts = |d|
  // with speed n dv (the discrete form of sqrt(2 a |d|), which would overshoot by one sample).
  const double n = -0.5 + std::sqrt(0.25 + 2.0 * std::abs(d) / (dv * l.Ts));
  double wanted = std::copysign(n * dv, d);
  wanted = std::clamp(wanted, -l.speed_neg_v_s, l.speed_pos_v_s);
  const double speed = std::clamp(wanted, s.speed_v_s - dv, s.speed_v_s + dv);
  double next = s.position_v + speed * l.Ts;
  // Within one sample's braking of the target, or past it: arrive and stop.
  if ((target_v - next) * d <= 0.0 || (std::abs(d) <= dv * l.Ts && std::abs(s.speed_v_s) <= dv)) {
    next = target_v;
    s.speed_v_s = 0.0;
  } else {
    s.speed_v_s = speed;
  }
  s.position_v = next;
  s.window[s.next] = next;
  s.next = (s.next + 1) % l.smoothing_samples;
  double sum = 0.0;  // summed afresh each sample: a running sum would drift over days
  bool at_rest = true;
  for (std::size_t i = 0; i < l.smoothing_samples; ++i) {
    sum += s.window[i];
    at_rest = at_rest && s.window[i] == next;
  }
  // A window all at one position is that position exactly: n copies of x summed and divided by n
  // can miss x by an ulp, and the laws' arrival tests compare the output with the target exactly
  // (pp-traj never arrived after such a halt: no integrator, no hold).
  return at_rest ? next : sum / static_cast<double>(l.smoothing_samples);
}

bool motion_profile_arrived(const MotionLimits& l, const MotionProfileState& s, double target_v) noexcept {
  if (s.position_v != target_v || s.speed_v_s != 0.0) return false;
  for (std::size_t i = 0; i < l.smoothing_samples; ++i)
    if (s.window[i] != target_v) return false;
  return true;
}

}  // namespace epa::control
