#pragma once
// The PLC-style scan cycle: every period Ts it applies queued commands, reads the sensor through
// the DAQ, checks for faults, steps the active controller (or holds the valve safe / manual, or
// steps the excitation experiment), writes the valve, records the sample and publishes a
// snapshot. One cycle never allocates, blocks on other threads, or does I/O other than the DAQ's.
//
// Timing (the same as sim::simulate_step): at cycle k the sensor is read, u(k) is computed and
// written at once, and held until k+1. Against the sim backend, which steps its plant on each
// write, a run through the scan cycle reproduces `epa simulate` sample for sample.
#include <atomic>
#include <cstdint>
#include <optional>

#include "control/bumpless_transfer.hpp"
#include "runtime/axis_motion.hpp"
#include "control/controller.hpp"
#include "hal/daq.hpp"
#include "runtime/clock.hpp"
#include "runtime/command.hpp"
#include "runtime/command_rules.hpp"
#include "runtime/excitation_run.hpp"
#include "runtime/fault_detector.hpp"
#include "runtime/fault_event.hpp"
#include "runtime/loop_channels.hpp"
#include "runtime/loop_stats.hpp"
#include "runtime/move_tracker.hpp"
#include "runtime/runtime_config.hpp"
#include "runtime/snapshot.hpp"
#include "runtime/tuning.hpp"

namespace epa::runtime {

class ScanCycle {
 public:
  // Allocates all buffers here. `config` must be valid (validate()) and period_s must equal Ts.
  ScanCycle(const RuntimeConfig& config, const Tuning& tuning, hal::Daq& daq, Clock& clock, LoopChannels& channels);

  // One cycle at wake time `now_ns`. noexcept and allocation-free.
  void cycle(std::int64_t now_ns) noexcept;

  // Sleeps to absolute deadlines and runs cycles until `stop` is set, measuring wake-up latency,
  // period jitter, compute time and overruns; then writes the safe valve command.
  void run(const std::atomic<bool>& stop) noexcept;

  // The last act of a shutdown or of the loop thread: valve to its safe command, mode STOP.
  void shut_down() noexcept;

  const Snapshot& last_snapshot() const noexcept { return snap_; }

 private:
  void apply_commands(std::int64_t now_ns) noexcept;
  void apply(const Command& c, std::int64_t now_ns) noexcept;
  void enter_run(std::int64_t now_ns) noexcept;
  void apply_control(const Command& c, std::int64_t now_ns) noexcept;
  void reset_fault() noexcept;  // FAULT -> STOP
  // A halt or a jog brakes along a profile, which pp-traj is made for: it runs them whenever the
  // tuning set's model allows it, whatever law is selected, and the selected law takes over again
  // (bumplessly) at the next start. law() is the one stepping.
  void use_profile_law(bool on) noexcept;
  // After the law's flags changed: the new law() takes over from `before` where the piston is.
  void take_over_from(control::ControllerKind before) noexcept;
  double plausible_speed_mm_s() const noexcept;  // the measured speed, within the model's top speeds
  control::ControllerKind law() const noexcept {
    return profile_law_ ? control::ControllerKind::kPpTraj : move_law_ ? *move_law_ : controller_;
  }
  // Runs the law towards `reference_mm` and sets valve_v_, controller_v_, saturated_ (or faults).
  void step_law(double reference_mm, double y_v) noexcept;
  // The calibrated position in sensor volts from the last reading: what the control laws read.
  double position_v() const noexcept;
  bool outside_soft_limits() const noexcept { return detector_.outside_soft_limits(position_mm_); }  // the last reading
  // Starts `law` on the piston where the last reading put it, at the speed of the last two readings.
  void start_law_at_the_piston(const control::ControllerParams& law) noexcept;
  void end_excitation(ExcitationEnd how) noexcept;
  // A started move (a setpoint written in RUN, or a start): the one before it ends cut short. A
  // record's own law runs this move only (the selected law, holding `controller`, stays), and
  // its side of approach (+1 below, -1 above, 0 near) this move's sliding arrival.
  void start_move(double target_mm, double speed_limit_mm_s, double window_mm,
                  std::optional<control::ControllerKind> record_law = std::nullopt, double approach_direction = 0.0) noexcept;
  // Adds this cycle's reading to the move and ends it when it has ended (in position, braked
  // after a halt, standing off target, or judged after move_window_s).
  void track_move() noexcept;
  void finish_move(MoveEnd end) noexcept;
  // The steps of a cycle, in order.
  bool read_sensor() noexcept;  // false: no reading this cycle (the last one stands)
  void check_faults(bool read_ok, std::int64_t now_ns) noexcept;
  void command_valve(bool read_ok, std::int64_t now_ns) noexcept;  // the mode's command, in valve_v_
  void write_valve(bool read_ok) noexcept;
  void record_sample() noexcept;

  void take_reading(double sensor_v) noexcept;  // the position and the speed from a reading
  void drive_run(bool read_ok) noexcept;        // the valve commands of the modes that drive
  void drive_jog(bool read_ok, std::int64_t now_ns) noexcept;
  void drive_excitation(bool read_ok) noexcept;
  void start_run_at_first_reading() noexcept;   // RUN entered: hold, or drive to the setpoint
  void enter_fault(FaultCode code) noexcept;
  void publish(bool full_stats = false) noexcept;

  RuntimeConfig config_;
  Tuning tuning_;
  hal::Daq& daq_;
  Clock& clock_;
  LoopChannels& ch_;
  std::int64_t period_ns_;

  Mode mode_ = Mode::kStop;
  FaultCode fault_ = FaultCode::kNone;
  control::ControllerKind controller_;  // the selected law (holding `controller`)
  std::optional<control::ControllerKind> move_law_;  // a record's own law, for its move only
  control::ControllerState state_;
  bool init_state_on_next_read_ = false;
  control::BumplessTransfer transfer_;  // a law or tuning switched in RUN takes over from the valve's command
  bool transfer_pending_ = false;       // start it at the next controller step
  double setpoint_mm_ = 0.0, manual_valve_v_ = 0.0;
  double sensor_v_ = 0.0, position_mm_ = 0.0, valve_v_ = 0.0, controller_v_ = 0.0;
  bool saturated_ = false, io_ok_ = true;
  bool hunting_ = false;  // the law's last output held the valve against a limit cycle
  FaultDetector detector_;  // the checks, and the I/O failures they count
  std::uint32_t heartbeat_ = 0;
  std::int64_t heartbeat_changed_ns_ = 0;
  std::uint64_t cycle_ = 0, faults_ = 0, applied_ = 0, rejected_ = 0;
  CommandRefusal last_refusal_ = CommandRefusal::kNone;
  std::uint64_t run_samples_end_ = 0;  // one past the last sample a controller drove (RUN): labels recordings

  ExcitationSettings excitation_settings_;  // what the next EXCITE starts with
  ExcitationRun excitation_;                // the running experiment

  MoveTracker moves_;
  MoveResult last_move_;

  // The positioning interface: the task and its reference, the control word and its handshake.
  AxisMotion motion_;
  std::uint16_t control_word_ = 0;
  bool hold_on_enable_ = false;         // RUN entered: hold at the first reading unless a move was started since
  bool jog_law_ = false;                // MANUAL: the law drives a jog (else the manual valve command)
  bool profile_law_ = false;            // pp-traj runs a halt or a jog in place of the selected law
  std::int64_t jog_keepalive_ns_ = 0;   // the heartbeat or control word last written while jogging
  double speed_mm_s_ = 0.0;             // measured, filtered
  double previous_position_mm_ = 0.0;   // the reading before position_mm_ (the speed spans two)
  int readings_ = 0;                    // up to 2: the speed needs two readings before this one
  std::uint64_t last_sequence_ = 0;
  LoopStats stats_;
  Snapshot snap_;  // fault_events_dropped is counted in it directly (enter_fault): publish() leaves it
};

}  // namespace epa::runtime
