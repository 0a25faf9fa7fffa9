#pragma once
// Everything the scan cycle needs to know besides the controller parameters, with the defaults
// of config/epa.toml. Validated once at start-up; the messages name the setting.
#include <cstddef>

#include "control/controller_kind.hpp"
#include "core/result.hpp"
#include "runtime/excitation_settings.hpp"
#include "runtime/mode.hpp"

namespace epa::runtime {

struct RuntimeConfig {
  double period_s = 0.005;          // Ts, must equal the model's sample time
  double mm_per_volt = 50.0;        // model units: position_mm = y * mm_per_volt
  double sensor_offset_v = 0.0;     // calibration: y = (sensor_v - offset) * gain
  double sensor_gain = 1.0;

  double sensor_min_v = -0.2, sensor_max_v = 10.2;  // outside: broken wire or wrong scaling
  double soft_min_mm = -2.0, soft_max_mm = 502.0;   // fault when the piston leaves them in RUN/MANUAL/EXCITE
  double setpoint_min_mm = 0.0, setpoint_max_mm = 500.0;
  double manual_valve_limit_v = 3.0;
  double safe_valve_v = 0.0;        // 5/3 valve centred
  double following_error_mm = 50.0; // |r - y| above this ...
  double following_error_time_s = 2.0;  // ... for longer than this faults (0: off)
  int max_consecutive_io_errors = 3;
  int max_consecutive_overruns = 10;
  double heartbeat_timeout_s = 0.0;  // 0: no heartbeat supervision
  // A reading that stays bit-identical for this long while |valve| > sensor_frozen_drive_v (beyond
  // the dead band: the piston must move) away from the ends of the setpoint range faults (0: off).
  double sensor_frozen_time_s = 0.5;
  double sensor_frozen_drive_v = 2.0;

  // pp-traj: it never overshoots on the paper's model, and without a friction model falls back
  // to arriving while sliding rather than hunt (docs/paper.md). The paper's pp-ffidz overshoots 57-157 % there.
  control::ControllerKind controller = control::ControllerKind::kPpTraj;
  Mode start_mode = Mode::kStop;
  double start_setpoint_mm = 0.0;
  FaultCode start_fault = FaultCode::kNone;  // latched from the first cycle (e.g. a damaged store)

  double move_window_s = 5.0;       // online metrics: each move is measured over this window
  double record_buffer_s = 60.0;    // recorder ring: seconds of history kept in memory (see below)
  double record_min_interval_s = 5.0;  // a record request (record_s) at most this often: one recording at a time

  ExcitationSettings excitation;    // the experiment of mode EXCITE, [excite]

  // [motion]: the positioning interface (status and control words, axis_motion.hpp).
  double in_position_window_mm = 1.0;  // in position: |target - position| <= this ...
  double in_position_time_s = 0.1;     // ... for this long
  double standstill_time_s = 0.5;      // a move whose piston stands (within the window's width) this long off target has ended
  double halt_decel_mm_s2 = 2500.0;    // a halt brakes the reference at this
  double jog_speed_mm_s = 20.0;        // jog: top speed, ...
  double jog_accel_mm_s2 = 500.0;      // ... acceleration and braking
  double jog_keepalive_s = 1.0;        // a jog brakes unless the heartbeat changes or the control word is written within this (0: off)
  // RUN entered holds the piston where it is (the setpoint follows it), so a retained or stale
  // setpoint never moves the axis; a start or a setpoint written in RUN moves it. false: RUN drives
  // to the setpoint (the behaviour before the positioning interface).
  bool enable_holds_position = true;
  // At start-up in RUN: drive to start_setpoint_mm (it was asked for explicitly), even when
  // enable_holds_position holds otherwise.
  bool start_moves_to_setpoint = false;
};

core::Status validate(const RuntimeConfig& config);

// The recorder ring's size in samples: record_buffer_s, or more when the configured excitation
// needs it (the whole experiment and kExcitationRecorderSlackS), so an experiment is written whole.
std::size_t record_capacity_samples(const RuntimeConfig& config);

}  // namespace epa::runtime
