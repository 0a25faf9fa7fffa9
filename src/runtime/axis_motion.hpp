#pragma once
// What the axis is doing, as an HMI asks it: the motion task (a move to a target, a halt, a jog),
// the reference the control law follows for it, and the status bits derived from it
// (moving, in position, target reached, halted, jogging). The scan cycle owns one; it is fixed
// size, allocation-free and noexcept, stepped once per cycle with the measured position.
//
// A move without a speed limit hands the law its target at once (the paper's laws are designed
// for steps); with one, the reference runs there on a trapezoidal profile. A halt brakes the
// reference from where the piston is, at its speed, to the point where braking at halt_decel
// stops it; a jog runs the reference towards the end of the range at the jog speed and brakes the
// same way when released. Positions in mm, speeds in mm/s (the profile is unit-agnostic).
#include <cstdint>

#include "control/motion_profile.hpp"

namespace epa::runtime {

// Filled from RuntimeConfig's [motion] settings (their defaults live there, once).
struct MotionConfig {
  double in_position_window_mm = 0;  // |target - position| at most this ...
  double in_position_time_s = 0;     // ... for this long: in position
  double standstill_time_s = 0;      // within one window's width for this long: the piston stands
  double halt_decel_mm_s2 = 0;       // braking of a halt
  double jog_speed_mm_s = 0;         // a jog's top speed
  double jog_accel_mm_s2 = 0;        // a jog's acceleration and braking
  double min_mm = 0, max_mm = 0;     // the setpoint range: a jog or a halt never aims beyond it
  double Ts = 0;
};

enum class MotionTask : std::uint8_t {
  kHold,  // at (or going to) a target with nothing started: RUN entered, or a move done
  kMove,  // a started move, until it is in position
  kHalt,  // braking to a stop, then holding there
  kJog,   // jogging, or braking after the jog was released
};

struct MotionStatus {
  bool moving = false;          // a move, halt or jog under way (not in position, not stood still off target)
  bool in_position = false;     // |target - position| <= window for in_position_time_s; the target is the
                                // last move's (or hold's): a halt short of it is not in position
  bool target_reached = false;  // the last started move came into position (cleared by the next start)
  bool halted = false;          // the last task was a halt (cleared by the next start)
  bool settled = false;         // the task has ended at its own end point (a halt: where it braked to)
  bool jogging = false;         // a jog or its braking is under way
  bool off_target = false;      // a move or halt has stopped outside its window: the piston stands, the law
                                // does not bring it in (a dead band, stiction); clears if it comes in later
};

class AxisMotion {
 public:
  explicit AxisMotion(const MotionConfig& config) noexcept;

  // Hold `position_mm`: nothing to do but stay (RUN entered with hold, or a reset of the task).
  void hold(double position_mm) noexcept;
  // A started move to `target_mm`. speed_limit_mm_s 0: the target at once; window_mm 0: the
  // configured in-position window.
  void move(double target_mm, double speed_limit_mm_s, double window_mm, double position_mm, double speed_mm_s) noexcept;
  // Brake from the piston's position and speed, then hold where it stopped.
  void halt(double position_mm, double speed_mm_s) noexcept;
  // direction +1 / -1: jog that way (from the piston's position and speed); 0: release (brake).
  void jog(int direction, double position_mm, double speed_mm_s) noexcept;

  // One cycle: advances the reference, the in-position timer and the standstill watch with the
  // measured position. Returns the reference for the control law, mm.
  double step(double position_mm) noexcept;

  double reference_mm() const noexcept { return reference_mm_; }
  double target_mm() const noexcept { return target_mm_; }  // where the task ends (a halt: its stop point)
  double goal_mm() const noexcept { return goal_mm_; }      // the target in_position is judged against
  MotionTask task() const noexcept { return task_; }
  // True while the reference still moves (a jog or a braking not yet at its end).
  bool profile_running() const noexcept { return profiled_ && !control::motion_profile_arrived(limits_, profile_, target_mm_); }
  MotionStatus status() const noexcept;

 private:
  void start_profile(double position_mm, double speed_mm_s, double top_speed_mm_s, double accel_mm_s2) noexcept;

  MotionConfig config_;
  MotionTask task_ = MotionTask::kHold;
  double target_mm_ = 0.0, reference_mm_ = 0.0, window_mm_ = 1.0;
  double goal_mm_ = 0.0;  // the last move's or hold's target; a halt or jog keeps it (jog: its stop point)
  bool profiled_ = false;  // the reference follows profile_ (else it is the target)
  control::MotionLimits limits_;
  control::MotionProfileState profile_;
  std::uint32_t samples_in_window_ = 0, samples_needed_ = 1;  // of target_mm_: the task has settled
  std::uint32_t samples_at_goal_ = 0;                          // of goal_mm_: in position
  bool settled_ = false, in_position_ = false, target_reached_ = false, halted_ = false;
  // Standstill: the range of positions since still_samples_ began stays within the window's width
  // (a window, not a speed: sensor noise makes a speed estimate at 200 Hz useless near zero).
  double still_min_mm_ = 0.0, still_max_mm_ = 0.0;
  std::uint32_t still_samples_ = 0, still_needed_ = 1;
  bool off_target_ = false;
  int jog_direction_ = 0;
};

}  // namespace epa::runtime
