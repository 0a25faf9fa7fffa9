#include "runtime/axis_motion.hpp"

#include <algorithm>
#include <cmath>

namespace epa::runtime {

AxisMotion::AxisMotion(const MotionConfig& config) noexcept
    : config_(config),
      window_mm_(config.in_position_window_mm),
      samples_needed_(static_cast<std::uint32_t>(std::max(1L, std::lround(config.in_position_time_s / config.Ts)))),
      still_needed_(static_cast<std::uint32_t>(std::max(1L, std::lround(config.standstill_time_s / config.Ts)))) {
  limits_.Ts = config.Ts;
}

void AxisMotion::hold(double position_mm) noexcept {
  task_ = MotionTask::kHold;
  target_mm_ = reference_mm_ = goal_mm_ = position_mm;
  window_mm_ = config_.in_position_window_mm;
  profiled_ = false;
  jog_direction_ = 0;
  samples_in_window_ = samples_at_goal_ = still_samples_ = 0;
  off_target_ = settled_ = in_position_ = target_reached_ = halted_ = false;
}

void AxisMotion::move(double target_mm, double speed_limit_mm_s, double window_mm, double position_mm, double speed_mm_s) noexcept {
  task_ = MotionTask::kMove;
  target_mm_ = goal_mm_ = target_mm;
  window_mm_ = window_mm > 0.0 ? window_mm : config_.in_position_window_mm;
  jog_direction_ = 0;
  samples_in_window_ = samples_at_goal_ = still_samples_ = 0;
  off_target_ = settled_ = in_position_ = target_reached_ = halted_ = false;
  if (speed_limit_mm_s > 0.0) {
    start_profile(position_mm, speed_mm_s, speed_limit_mm_s, config_.halt_decel_mm_s2);
  } else {
    profiled_ = false;
    reference_mm_ = target_mm;
  }
}

void AxisMotion::halt(double position_mm, double speed_mm_s) noexcept {
  const double a = config_.halt_decel_mm_s2;
  const double v = std::isfinite(speed_mm_s) ? speed_mm_s : 0.0;
  task_ = MotionTask::kHalt;
  target_mm_ = std::clamp(position_mm + v * std::abs(v) / (2.0 * a), config_.min_mm, config_.max_mm);
  // The move's window and target stay: in position is still judged against the target it was
  // going to, which a halt short of it has not reached.
  jog_direction_ = 0;
  samples_in_window_ = samples_at_goal_ = still_samples_ = 0;
  off_target_ = settled_ = in_position_ = target_reached_ = false;
  halted_ = true;
  start_profile(position_mm, v, std::max(std::abs(v), 1.0), a);
}

void AxisMotion::jog(int direction, double position_mm, double speed_mm_s) noexcept {
  if (direction == 0) {
    if (task_ != MotionTask::kJog || jog_direction_ == 0) return;  // nothing to release
    // Brake from where the reference is (the piston follows it), at the jog's own braking.
    const double v = profile_.speed_v_s;
    jog_direction_ = 0;
    target_mm_ = goal_mm_ = std::clamp(profile_.position_v + v * std::abs(v) / (2.0 * config_.jog_accel_mm_s2), config_.min_mm, config_.max_mm);
    return;
  }
  task_ = MotionTask::kJog;
  jog_direction_ = direction > 0 ? 1 : -1;
  target_mm_ = goal_mm_ = jog_direction_ > 0 ? config_.max_mm : config_.min_mm;
  window_mm_ = config_.in_position_window_mm;
  samples_in_window_ = samples_at_goal_ = still_samples_ = 0;
  off_target_ = settled_ = in_position_ = target_reached_ = halted_ = false;
  start_profile(position_mm, speed_mm_s, config_.jog_speed_mm_s, config_.jog_accel_mm_s2);
}

void AxisMotion::start_profile(double position_mm, double speed_mm_s, double top_speed_mm_s, double accel_mm_s2) noexcept {
  limits_.speed_pos_v_s = limits_.speed_neg_v_s = top_speed_mm_s;
  limits_.accel_v_s2 = accel_mm_s2;
  limits_.accel_per_distance = 0.0;
  limits_.smoothing_samples = 1;
  control::motion_profile_reset(limits_, profile_, position_mm, speed_mm_s);
  profiled_ = true;
  reference_mm_ = position_mm;
}

double AxisMotion::step(double position_mm) noexcept {
  if (profiled_) reference_mm_ = control::motion_profile_step(limits_, profile_, target_mm_);
  const bool jog_running = task_ == MotionTask::kJog && (jog_direction_ != 0 || profile_running());
  const bool steady = !jog_running && !profile_running();
  auto dwell = [&](double at_mm, std::uint32_t& samples) {
    if (steady && std::abs(at_mm - position_mm) <= window_mm_) samples = std::min(samples + 1, samples_needed_);
    else samples = 0;
    return samples >= samples_needed_;
  };
  settled_ = dwell(target_mm_, samples_in_window_);
  in_position_ = dwell(goal_mm_, samples_at_goal_);
  if (in_position_ && task_ == MotionTask::kMove) target_reached_ = true;

  // A move or halt whose reference has arrived and whose piston stands outside the window has
  // ended there: a client waiting for moving to clear must not wait for ever.
  if (std::isfinite(position_mm) && still_samples_ > 0 && std::max(still_max_mm_, position_mm) - std::min(still_min_mm_, position_mm) <= window_mm_) {
    still_min_mm_ = std::min(still_min_mm_, position_mm);
    still_max_mm_ = std::max(still_max_mm_, position_mm);
    if (still_samples_ < still_needed_) ++still_samples_;
  } else {
    still_min_mm_ = still_max_mm_ = position_mm;
    still_samples_ = std::isfinite(position_mm) ? 1 : 0;
  }
  const bool ending_task = task_ == MotionTask::kMove || task_ == MotionTask::kHalt;
  off_target_ = ending_task && !settled_ && !profile_running() && still_samples_ >= still_needed_;
  if (task_ == MotionTask::kJog && !jog_running) task_ = MotionTask::kHold;  // braked: holding where the jog stopped
  return reference_mm_;
}

MotionStatus AxisMotion::status() const noexcept {
  MotionStatus s;
  s.jogging = task_ == MotionTask::kJog;
  s.in_position = in_position_;
  s.settled = settled_;
  s.target_reached = target_reached_;
  s.halted = halted_;
  s.off_target = off_target_;
  s.moving = s.jogging || ((task_ == MotionTask::kMove || task_ == MotionTask::kHalt) && !settled_ && !off_target_);
  return s;
}

}  // namespace epa::runtime
