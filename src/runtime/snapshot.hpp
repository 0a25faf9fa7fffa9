#pragma once
// Snapshot out: everything the other threads may know of the loop, published once per cycle
// through a SeqlockCell. Trivially copyable: plain numbers, NaN for "never" / "no value".
#include <array>
#include <cstdint>

#include "control/controller_kind.hpp"
#include "control/rst_law.hpp"
#include "control/trajectory_law.hpp"
#include "core/dead_zone.hpp"
#include "core/sensor_calibration.hpp"
#include "runtime/command_rules.hpp"
#include "runtime/excitation_settings.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/mode.hpp"

namespace epa::runtime {

struct MoveMetricsView {
  std::uint32_t number = 0;  // 0: no move finished yet
  double from_mm = 0, to_mm = 0;
  double rise_s = 0, settling_s = 0, ess_mm = 0, overshoot_pct = 0;  // NaN: n/a (core/move_metrics.hpp)
  std::uint8_t end = 0;      // core::MoveEnd: 0 in position, 1 cut short, 2 halted, 3 stopped, 4 fault,
                             // 5 controller switched, 6 timeout, 7 off target
  control::ControllerKind controller = control::ControllerKind::kPpFfidz;  // the law that ran the move
};

struct TuningView {
  std::array<double, control::kMaxLawOrder + 1> F{}, G{}, H{};
  std::uint8_t nF = 0, nG = 0, nH = 0;
  double m_r = 0, m_l = 0, b_r = 0, b_l = 0, lc_mm = 0, valve_limit_v = 0;
  double traj_speed_fraction = 0, traj_bandwidth_rad_s = 0, traj_hold_band_mm = 0;  // pp-traj's settings

  // The writable settings (the tuning points), in the units the points show: the loop fills them
  // from what runs, the write gate from what it has accepted and the loop has not taken yet.
  void set_writable(const core::DeadZone& dz, double lc_v, const control::TrajectoryConfig& traj, core::SensorCalibration sensor) noexcept {
    m_r = dz.m_r, m_l = dz.m_l, b_r = dz.b_r, b_l = dz.b_l;
    lc_mm = sensor.to_mm(lc_v);
    traj_speed_fraction = traj.speed_fraction;
    traj_bandwidth_rad_s = traj.feedback_bandwidth_rad_s;
    traj_hold_band_mm = sensor.to_mm(traj.hold_band_v);
  }
};

// The positioning interface's state (axis_words.hpp composes the status word from it).
struct AxisView {
  bool moving = false, in_position = false, target_reached = false, following_error = false;
  bool ack = false, halted = false, jogging = false;
  std::uint16_t control_word = 0;  // as the loop last applied it
  double reference_mm = 0;         // what the control law follows (a halt's or jog's profile, or the target)
  double speed_mm_s = 0;           // measured, filtered (20 ms)
  bool off_target = false;         // the last move or halt stopped outside its window (RUN)
  bool hunting = false;            // the law's hunting watch holds the valve centred (RUN; control/hunting_guard.hpp)
};

struct Snapshot {
  std::uint64_t cycle = 0;
  double time_s = 0;  // since start, cycle * Ts
  double Ts = 0;
  Mode mode = Mode::kStop;
  FaultCode fault = FaultCode::kNone;  // the latched fault (kNone unless mode is kFault)
  control::ControllerKind controller = control::ControllerKind::kPpFfidz;  // the selected law (holding controller)
  control::ControllerKind running_law = control::ControllerKind::kPpFfidz;  // the one stepping now: a record's own
                                                                           // for its move, pp-traj braking a halt or jog
  bool saturated = false;
  bool io_ok = true;  // the last read and write both succeeded
  double setpoint_mm = 0, position_mm = 0, sensor_v = 0, error_mm = 0;
  double valve_v = 0, controller_v = 0, manual_valve_v = 0;
  std::uint32_t heartbeat = 0;
  std::uint64_t moves = 0, faults = 0, io_errors = 0, commands_applied = 0, commands_rejected = 0;
  CommandRefusal last_refusal = CommandRefusal::kNone;  // why the loop last refused a command
  std::uint64_t fault_events_dropped = 0;  // faults the fault_events ring had no room for: not in the history
  ExcitationSettings excitation;  // what the next EXCITE starts with
  double excitation_left_s = 0;   // of the running experiment; 0 when none runs
  MoveMetricsView last_move;
  AxisView axis;
  std::uint64_t last_sequence = 0;  // the last command the loop took, applied or refused (Command::sequence)
  LoopStatsView loop;
  TuningView tuning;
};

}  // namespace epa::runtime
