#include "runtime/scan_cycle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/axis_words.hpp"

namespace epa::runtime {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kSpeedFilterS = 0.02;  // the measured speed's low-pass (a halt brakes from it)

MotionConfig motion_config(const RuntimeConfig& c) {
  return {.in_position_window_mm = c.in_position_window_mm, .in_position_time_s = c.in_position_time_s,
          .standstill_time_s = c.standstill_time_s,
          .halt_decel_mm_s2 = c.halt_decel_mm_s2, .jog_speed_mm_s = c.jog_speed_mm_s, .jog_accel_mm_s2 = c.jog_accel_mm_s2,
          .min_mm = c.setpoint_min_mm, .max_mm = c.setpoint_max_mm, .Ts = c.period_s};
}
}  // namespace

ScanCycle::ScanCycle(const RuntimeConfig& config, const Tuning& tuning, hal::Daq& daq, Clock& clock, LoopChannels& ch)
    : config_(config),
      tuning_(tuning),
      daq_(daq),
      clock_(clock),
      ch_(ch),
      period_ns_(static_cast<std::int64_t>(std::llround(config.period_s * 1e9))),
      controller_(config.controller),
      transfer_(0.05, config.period_s),
      setpoint_mm_(config.start_setpoint_mm),
      manual_valve_v_(config.safe_valve_v),
      valve_v_(config.safe_valve_v),
      detector_(config),
      excitation_settings_(config.excitation),
      moves_(ch.samples.capacity(), config.move_window_s, config.period_s, config.in_position_time_s),
      motion_(motion_config(config)) {
  if (config.start_fault != FaultCode::kNone) {
    mode_ = Mode::kFault;  // before any start mode: a fault found before the start is latched
    fault_ = config.start_fault;
    faults_ = 1;
    // In the history too; it never ran (STOP) and has read nothing yet (NaN).
    ch_.fault_events.try_push({0, 0.0, fault_, Mode::kStop, kNaN, setpoint_mm_, valve_v_, kNaN});  // the ring is empty
  } else if (config.start_mode == Mode::kRun) {
    mode_ = Mode::kRun;
    init_state_on_next_read_ = true;  // the position is known only after the first read
    hold_on_enable_ = config.enable_holds_position && !config.start_moves_to_setpoint;
  }
  heartbeat_changed_ns_ = clock_.now_ns();
  publish();
}

void ScanCycle::apply_commands(std::int64_t now_ns) noexcept {
  // Everything queued now, so a group pushed with try_push_all is never split across cycles;
  // bounded by the queue's capacity.
  Command c;
  for (std::size_t i = 0; i < kCommandQueueCapacity && ch_.commands.try_pop(c); ++i) apply(c, now_ns);
}

void ScanCycle::apply(const Command& c, std::int64_t now_ns) noexcept {
  last_sequence_ = c.sequence;
  CommandRefusal refusal = check_command(c, mode_, position_mm_, excitation_settings_, control_word_, config_);
  if (refusal == CommandRefusal::kNone) {
    switch (c.kind) {
      case CommandKind::kSetpoint:
        // A setpoint written in RUN moves when it changes (an HMI may write the same one every
        // poll), and also when RUN was just entered and has not yet held: then the client chose
        // it with the enable, even if it is the one it wrote before.
        if (c.value != setpoint_mm_ || (mode_ == Mode::kRun && hold_on_enable_)) {
          setpoint_mm_ = c.value;
          if (mode_ == Mode::kRun) start_move(c.value, 0.0, 0.0);
        }
        break;
      case CommandKind::kMode:
        if (c.mode != mode_) {
          // Entered from STOP only (check_command), so no move or experiment is under way here.
          if (c.mode == Mode::kExcite && !excitation_.start(excitation_settings_, config_, ch_.samples.written())) {
            refusal = CommandRefusal::kExcitationInvalid;  // cannot happen: the settings were checked when taken
            break;
          }
          if (moves_.active()) finish_move(MoveEnd::kStopped);
          if (mode_ == Mode::kExcite) end_excitation(ExcitationEnd::kStopped);
          jog_law_ = profile_law_ = false;
          if (c.mode == Mode::kRun) enter_run(now_ns);
          if (c.mode == Mode::kManual) {
            manual_valve_v_ = config_.safe_valve_v;  // never resume a stale manual command
            heartbeat_changed_ns_ = now_ns;
            motion_.hold(position_mm_);
          }
          if (c.mode == Mode::kExcite) heartbeat_changed_ns_ = now_ns;  // the client gets a full timeout from here
          if ((c.mode == Mode::kRun || c.mode == Mode::kManual) && readings_ > 0 && outside_soft_limits())
            detector_.allow_recovery_from(position_mm_);
          else
            detector_.hold_soft_limits();
          if (mode_ == Mode::kManual) manual_valve_v_ = config_.safe_valve_v;  // it ends with MANUAL (read back so)
          mode_ = c.mode;
        }
        break;
      case CommandKind::kManualValve: manual_valve_v_ = c.value; break;
      case CommandKind::kController:
        if (c.controller == control::ControllerKind::kPpTraj && !tuning_.traj_available) {
          refusal = CommandRefusal::kControllerUnavailable;
          break;
        }
        // A move's record, metrics and run file belong to the law that made it: a switch ends
        // it here (the piston goes on to its target under the new law, not as a move).
        if (c.controller != controller_ && moves_.active()) finish_move(MoveEnd::kControllerSwitched);
        {
          const control::ControllerKind before = law();
          controller_ = c.controller;
          profile_law_ = false;  // the law asked for runs from now on, a halt's hold included
          move_law_.reset();
          take_over_from(before);
        }
        break;
      case CommandKind::kTuning:  // takes effect in this cycle's step, whole, taking over from the valve's command
        if (controller_ == control::ControllerKind::kPpTraj && !c.tuning.traj_available) {
          refusal = CommandRefusal::kControllerUnavailable;  // pp-traj runs: a set it cannot use is not taken
          break;
        }
        tuning_ = c.tuning;
        if ((profile_law_ || move_law_ == control::ControllerKind::kPpTraj) && !tuning_.traj_available) {
          // a halt's, jog's or record's pp-traj cannot go on: the selected law takes over
          profile_law_ = false;
          move_law_.reset();
          start_law_at_the_piston(tuning_.for_kind(controller_));
        }
        if (law() == control::ControllerKind::kPpTraj) start_law_at_the_piston(tuning_.traj);  // new limits: a new profile
        transfer_pending_ = mode_ == Mode::kRun;
        break;
      case CommandKind::kReset: reset_fault(); break;
      case CommandKind::kHeartbeat:
        if (c.heartbeat != heartbeat_) {
          heartbeat_ = c.heartbeat;
          heartbeat_changed_ns_ = now_ns;
          jog_keepalive_ns_ = now_ns;
        }
        break;
      case CommandKind::kControl: apply_control(c, now_ns); break;
      case CommandKind::kRecord: {
        RecordRequest r;
        r.end = ch_.samples.written();
        const auto n = static_cast<std::uint64_t>(c.value / config_.period_s);
        r.first = r.end > n ? r.end - n : 0;
        r.controller = controller_;
        r.open_loop = run_samples_end_ <= r.first;  // MANUAL, EXCITE, STOP only: no controller in the loop
        if (!ch_.record_requests.try_push(r)) refusal = CommandRefusal::kRecordQueueFull;
        break;
      }
      case CommandKind::kExcitation: excitation_settings_ = c.excitation; break;  // for the next EXCITE
    }
  }
  if (refusal == CommandRefusal::kNone) {
    ++applied_;
    return;
  }
  ++rejected_;
  last_refusal_ = refusal;
  ch_.refusals.try_push({c.sequence, refusal});  // full: the count and last_refusal still tell
}

double ScanCycle::position_v() const noexcept { return (sensor_v_ - config_.sensor_offset_v) * config_.sensor_gain; }

// The same speed a halt brakes from: a one-sample difference would start pp-traj's profile from
// one sample of sensor noise or of the printed B's spike.
void ScanCycle::start_law_at_the_piston(const control::ControllerParams& law) noexcept {
  control::controller_start(law, state_, position_v(), plausible_speed_mm_s() / config_.mm_per_volt);
}

void ScanCycle::enter_run(std::int64_t now_ns) noexcept {
  init_state_on_next_read_ = true;
  hold_on_enable_ = config_.enable_holds_position;  // until a move is started before the first reading
  heartbeat_changed_ns_ = now_ns;  // the client gets a full timeout from here
  detector_.restart_following_error();
  motion_.hold(position_mm_);
  detector_.following().follow_reference(position_mm_);
}

void ScanCycle::use_profile_law(bool on) noexcept {
  if (on == profile_law_ || (on && !tuning_.traj_available)) return;
  const control::ControllerKind before = law();
  profile_law_ = on;
  take_over_from(before);
}

void ScanCycle::take_over_from(control::ControllerKind before) noexcept {
  if (law() == before) return;
  // The RST laws share their history; pp-traj keeps its own, so a switch to or from it starts the
  // new law where the piston is, at its speed. Either way the valve command does not step: the new
  // law takes over from it (bumpless transfer) when a law is driving (RUN, or a jog).
  if ((before == control::ControllerKind::kPpTraj) != (law() == control::ControllerKind::kPpTraj))
    start_law_at_the_piston(tuning_.for_kind(law()));
  transfer_pending_ = mode_ == Mode::kRun || jog_law_;
}

double ScanCycle::plausible_speed_mm_s() const noexcept {
  if (!tuning_.traj_available) return speed_mm_s_;
  // No faster than the model at the valve limit: beyond it a reading is a spike, not a speed (the
  // printed B answers each valve jump with one), and a halt would aim at the end of the stroke.
  const auto& t = tuning_.traj;
  const double fraction = t.trajectory_config().speed_fraction;
  const auto& limits = t.trajectory().limits;
  return std::clamp(speed_mm_s_, -limits.speed_neg_v_s / fraction * config_.mm_per_volt, limits.speed_pos_v_s / fraction * config_.mm_per_volt);
}

void ScanCycle::reset_fault() noexcept {
  if (mode_ != Mode::kFault) return;  // nothing latched: nothing to do, and that is fine
  mode_ = Mode::kStop;
  fault_ = FaultCode::kNone;
  detector_.reset();
}

void ScanCycle::apply_control(const Command& c, std::int64_t now_ns) noexcept {
  const std::uint16_t word = c.control_word & kControlWordMask;
  const std::uint16_t rising = word & static_cast<std::uint16_t>(~control_word_);
  control_word_ = word;
  jog_keepalive_ns_ = now_ns;  // any control word written keeps a jog alive
  if (rising & kControlReset) reset_fault();
  if (rising & kControlHalt) {
    if (mode_ == Mode::kRun) {
      // A move under way goes on being recorded through the braking, and ends halted once it
      // stands (track_move).
      use_profile_law(true);
      motion_.halt(position_mm_, plausible_speed_mm_s());
      detector_.following().follow_reference(position_mm_);
      setpoint_mm_ = motion_.target_mm();  // the setpoint tells where the axis now stops
      hold_on_enable_ = false;
    } else if (jog_law_) {
      motion_.jog(0, position_mm_, speed_mm_s_);
    }
  }
  if (rising & kControlStart) {  // checked: RUN, a target within the setpoint range
    setpoint_mm_ = c.value;
    start_move(c.value, c.speed_limit_mm_s, c.window_mm, c.start_controller ? std::optional(c.controller) : std::nullopt,
               c.approach_direction);
  }
  if (mode_ == Mode::kManual) {
    const bool plus = word & kControlJogPlus, minus = word & kControlJogMinus;
    const int direction = plus == minus ? 0 : plus ? 1 : -1;  // both held: neither
    if (direction != 0 && (rising & (kControlJogPlus | kControlJogMinus))) {
      if (!jog_law_) {  // the law takes over from the manual valve command where the piston is
        profile_law_ = tuning_.traj_available;
        start_law_at_the_piston(tuning_.for_kind(law()));
        transfer_pending_ = true;
        jog_law_ = true;
      }
      manual_valve_v_ = config_.safe_valve_v;  // after the jog: the valve rests
      motion_.jog(direction, position_mm_, speed_mm_s_);
      detector_.following().follow_reference(position_mm_);
    } else if (direction == 0 && jog_law_) {
      motion_.jog(0, position_mm_, speed_mm_s_);
    }
  }
}

void ScanCycle::end_excitation(ExcitationEnd how) noexcept {
  RecordRequest r;
  r.reason = RecordRequest::Reason::kExcitation;
  r.first = excitation_.first_sample();
  r.end = ch_.samples.written();  // this cycle's sample is not the experiment's
  r.controller = controller_;
  r.open_loop = true;
  r.excitation = excitation_.settings();
  r.excitation_end = how;
  r.pulses = static_cast<std::uint32_t>(excitation_.pulses());
  r.pulses_cut = static_cast<std::uint32_t>(excitation_.pulses_cut());
  excitation_.end();
  if (r.end > r.first) ch_.record_requests.try_push(r);  // a full queue drops the file, never the loop
}

void ScanCycle::start_move(double target_mm, double speed_limit_mm_s, double window_mm,
                           std::optional<control::ControllerKind> record_law, double approach_direction) noexcept {
  if (moves_.active()) finish_move(MoveEnd::kCutShort);
  hold_on_enable_ = false;  // RUN entered with a move: the move, not a hold
  const control::ControllerKind before = law();
  profile_law_ = false;  // after a halt: the selected law again, taking over bumplessly
  // A record's law pp-traj on a model it cannot run on: the move runs with the selected law (its
  // record says so).
  const bool usable = record_law && (*record_law != control::ControllerKind::kPpTraj || tuning_.traj_available);
  move_law_ = usable && *record_law != controller_ ? record_law : std::nullopt;
  take_over_from(before);
  control::controller_new_move(state_, approach_direction);  // a start to the same target is a new try, watched afresh
  moves_.start(position_mm_, target_mm, law(), ch_.samples.written());
  motion_.move(target_mm, speed_limit_mm_s, window_mm, position_mm_, speed_mm_s_);
  if (speed_limit_mm_s > 0.0) {
    detector_.following().follow_reference(position_mm_);
  } else {
    const auto& planned = tuning_.traj.trajectory().limits;  // sensor volts: in mm for the watch
    control::MotionLimits expected = planned;
    expected.speed_pos_v_s *= config_.mm_per_volt;
    expected.speed_neg_v_s *= config_.mm_per_volt;
    expected.accel_v_s2 *= config_.mm_per_volt;
    detector_.following().start_step(expected, tuning_.traj_available, position_mm_, plausible_speed_mm_s());
  }
}

void ScanCycle::track_move() noexcept {
  const bool judge = moves_.add(position_mm_, !motion_.profile_running());
  const MotionStatus m = motion_.status();
  if (motion_.task() == MotionTask::kHalt) {
    if (!m.moving || judge) finish_move(MoveEnd::kHalted);  // braked and standing (or judged)
  } else if (m.in_position) {
    finish_move(MoveEnd::kInPosition);
  } else if (m.off_target) {
    finish_move(MoveEnd::kOffTarget);
  } else if (judge) {
    finish_move(MoveEnd::kTimeout);
  }
}

void ScanCycle::finish_move(MoveEnd end) noexcept {
  last_move_ = moves_.finish(end);
  RecordRequest r;
  r.reason = RecordRequest::Reason::kMove;
  r.first = last_move_.first_sample;
  r.end = last_move_.end_sample;
  r.move = last_move_;
  r.controller = last_move_.controller;
  r.ess_window_s = moves_.options().ess_window_s;
  ch_.record_requests.try_push(r);  // a full queue drops the file, never the loop
  if (move_law_) {  // the record's law ran this move only: the selected one takes over again
    const control::ControllerKind before = law();
    move_law_.reset();
    take_over_from(before);
  }
}

void ScanCycle::enter_fault(FaultCode code) noexcept {
  // The cause, as it is before anything below changes it: a reset in the next cycle clears the
  // snapshot's fault, never this. A full ring drops it, counted.
  if (!ch_.fault_events.try_push({cycle_, static_cast<double>(cycle_) * config_.period_s, code, mode_, position_mm_,
                                  setpoint_mm_, valve_v_, sensor_v_, detector_.failed_reads(), detector_.failed_writes(),
                                  detector_.last_read(), detector_.last_write()}))
    ++snap_.fault_events_dropped;
  if (moves_.active()) finish_move(MoveEnd::kFault);
  jog_law_ = profile_law_ = false;
  if (mode_ == Mode::kExcite) end_excitation(ExcitationEnd::kFault);
  manual_valve_v_ = config_.safe_valve_v;  // a manual command ends with MANUAL: it reads back as the safe one
  mode_ = Mode::kFault;
  fault_ = code;
  ++faults_;
}

void ScanCycle::cycle(std::int64_t now_ns) noexcept {
  apply_commands(now_ns);
  const bool read_ok = read_sensor();
  if (mode_ != Mode::kFault) check_faults(read_ok, now_ns);
  command_valve(read_ok, now_ns);
  write_valve(read_ok);
  record_sample();
  ++cycle_;
  publish();
}

bool ScanCycle::read_sensor() noexcept {
  const hal::SensorReading reading = daq_.read_sensor();
  detector_.count_read(reading);  // before the checks: the N-th failure faults this cycle
  if (reading.status != hal::IoStatus::kOk) return false;
  take_reading(reading.sensor_v);
  // RUN from the start, with the first reading outside the soft limits: it may be brought back
  // in, as when RUN is entered by command.
  if (init_state_on_next_read_ && readings_ == 1 && outside_soft_limits()) detector_.allow_recovery_from(position_mm_);
  return true;
}

void ScanCycle::take_reading(double sensor_v) noexcept {
  sensor_v_ = sensor_v;
  const double two_back_mm = previous_position_mm_;
  previous_position_mm_ = position_mm_;
  position_mm_ = (sensor_v_ - config_.sensor_offset_v) * config_.sensor_gain * config_.mm_per_volt;
  // Over two samples: a plant ringing at the Nyquist rate (the paper's B under FF-IDZ) alternates
  // its readings, which this difference cancels, so a halt brakes from the piston's real speed.
  const double raw_speed = (position_mm_ - two_back_mm) / (2.0 * config_.period_s);
  if (readings_ >= 2 && std::isfinite(raw_speed)) speed_mm_s_ += (raw_speed - speed_mm_s_) * (config_.period_s / (kSpeedFilterS + config_.period_s));
  if (readings_ < 2) ++readings_;
}

void ScanCycle::check_faults(bool read_ok, std::int64_t now_ns) noexcept {
  const CycleView view{
      .mode = mode_, .read_ok = read_ok, .sensor_v = sensor_v_, .position_mm = position_mm_, .valve_v = valve_v_,
      .heartbeat_changed_ns = heartbeat_changed_ns_, .reference_mm = motion_.reference_mm(), .target_mm = motion_.target_mm(),
      .following_position_mm = readings_ >= 2 ? 0.5 * (position_mm_ + previous_position_mm_) : position_mm_};
  if (const FaultCode f = detector_.check(view, now_ns); f != FaultCode::kNone) enter_fault(f);
}

void ScanCycle::command_valve(bool read_ok, std::int64_t now_ns) noexcept {
  saturated_ = false;
  switch (mode_) {
    case Mode::kRun: drive_run(read_ok); break;
    case Mode::kManual:
      if (jog_law_) {
        drive_jog(read_ok, now_ns);
      } else {
        valve_v_ = manual_valve_v_;
        controller_v_ = 0.0;
      }
      break;
    case Mode::kExcite: drive_excitation(read_ok); break;
    case Mode::kStop:
    case Mode::kFault: valve_v_ = config_.safe_valve_v; controller_v_ = 0.0; break;
  }
}

void ScanCycle::drive_run(bool read_ok) noexcept {
  if (!read_ok) return;  // hold the last command for a missed sample (counted by the detector)
  const double y_v = position_v();
  if (init_state_on_next_read_) start_run_at_first_reading();
  step_law(motion_.step(position_mm_), y_v);
}

// The law drives the jog (holding the last command for a missed sample).
void ScanCycle::drive_jog(bool read_ok, std::int64_t now_ns) noexcept {
  if (!read_ok) return;
  if (config_.jog_keepalive_s > 0.0 && static_cast<double>(now_ns - jog_keepalive_ns_) > config_.jog_keepalive_s * 1e9)
    motion_.jog(0, position_mm_, speed_mm_s_);  // no keep-alive: brake as if released
  step_law(motion_.step(position_mm_), position_v());
  if (mode_ == Mode::kManual && motion_.task() != MotionTask::kJog) jog_law_ = profile_law_ = false;  // braked: the manual command next
}

void ScanCycle::drive_excitation(bool read_ok) noexcept {
  controller_v_ = 0.0;
  if (excitation_.done()) {  // every command given: STOP by itself, the valve safe in this cycle
    end_excitation(ExcitationEnd::kComplete);
    mode_ = Mode::kStop;
    valve_v_ = config_.safe_valve_v;
    return;
  }
  if (!read_ok) return;  // hold the last command for a missed sample, as RUN does
  valve_v_ = excitation_.next(position_mm_);
}

void ScanCycle::start_run_at_first_reading() noexcept {
  // At rest at the current position: no error history, no controller output history.
  profile_law_ = false;
  control::controller_start(tuning_.for_kind(controller_), state_, position_v(), 0.0);
  init_state_on_next_read_ = false;
  transfer_pending_ = false;  // RUN starts from the safe valve command, not from another law
  if (hold_on_enable_) {      // enable holds: the setpoint follows the piston, nothing moves
    setpoint_mm_ = position_mm_;
    motion_.hold(position_mm_);
    hold_on_enable_ = false;
  } else if (!moves_.active()) {  // RUN drives to the setpoint (enable_holds_position off, or asked at start)
    if (setpoint_mm_ != position_mm_) start_move(setpoint_mm_, 0.0, 0.0);
    else motion_.hold(setpoint_mm_);
  }
}

void ScanCycle::write_valve(bool read_ok) noexcept {
  const hal::IoStatus status = daq_.write_valve(valve_v_);
  detector_.count_write(status);  // a valve that cannot be written faults at the next cycle's check
  io_ok_ = read_ok && status == hal::IoStatus::kOk;
}

void ScanCycle::record_sample() noexcept {
  ch_.samples.push({static_cast<double>(cycle_) * config_.period_s, setpoint_mm_, position_mm_, valve_v_, controller_v_});
  if (mode_ == Mode::kRun) run_samples_end_ = ch_.samples.written();
  if (mode_ == Mode::kRun && moves_.active()) track_move();
}

void ScanCycle::step_law(double reference_mm, double y_v) noexcept {
  const auto out = control::controller_step(tuning_.for_kind(law()), state_, reference_mm / config_.mm_per_volt, y_v);
  if (out.fault) {
    enter_fault(FaultCode::kControllerFault);
    valve_v_ = config_.safe_valve_v;
    return;
  }
  if (transfer_pending_) transfer_.start(valve_v_, out.valve_v);
  transfer_pending_ = false;
  const double limit_v = tuning_.for_kind(law()).valve_limit_v();
  valve_v_ = std::clamp(transfer_.apply(out.valve_v), -limit_v, limit_v);
  controller_v_ = out.controller_v;
  saturated_ = out.saturated;
  hunting_ = out.hunting;
}

void ScanCycle::publish(bool full_stats) noexcept {
  Snapshot& s = snap_;
  s.cycle = cycle_;
  s.time_s = static_cast<double>(cycle_) * config_.period_s;
  s.Ts = config_.period_s;
  s.mode = mode_;
  s.fault = fault_;
  s.controller = controller_;
  s.running_law = law();
  s.saturated = saturated_;
  s.io_ok = io_ok_;
  s.setpoint_mm = setpoint_mm_;
  s.position_mm = position_mm_;
  s.sensor_v = sensor_v_;
  s.error_mm = setpoint_mm_ - position_mm_;
  s.valve_v = valve_v_;
  s.controller_v = controller_v_;
  s.manual_valve_v = manual_valve_v_;
  s.heartbeat = heartbeat_;
  s.moves = last_move_.number;
  s.faults = faults_;
  s.io_errors = detector_.io_errors();
  s.commands_applied = applied_;
  s.commands_rejected = rejected_;
  s.last_refusal = last_refusal_;
  s.excitation = excitation_settings_;
  s.excitation_left_s = excitation_.left_s();
  const auto& m = last_move_.metrics;
  s.last_move = {last_move_.number, last_move_.from_mm, last_move_.to_mm, m.rise_s, m.settling_s,
                 last_move_.number ? m.ess_mm : kNaN, m.overshoot_pct, static_cast<std::uint8_t>(last_move_.end),
                 last_move_.controller};
  const MotionStatus motion = motion_.status();
  const bool axis_active = mode_ == Mode::kRun || (mode_ == Mode::kManual && jog_law_);
  s.axis = {axis_active && motion.moving, mode_ == Mode::kRun && motion.in_position, mode_ == Mode::kRun && motion.target_reached,
            mode_ == Mode::kRun && detector_.following_error_shown(), (control_word_ & kControlStart) != 0, motion.halted, axis_active && motion.jogging,
            control_word_, axis_active ? motion_.reference_mm() : position_mm_, speed_mm_s_, mode_ == Mode::kRun && motion.off_target,
            mode_ == Mode::kRun && hunting_};
  s.last_sequence = last_sequence_;
  if (cycle_ % 200 == 0 || full_stats) s.loop = stats_.view();  // percentiles scan the bins: a few times a second
  s.loop.overruns = stats_.overruns;
  const auto& p = tuning_.for_kind(controller_);
  const auto& rst = p.rst();
  s.tuning = {};
  s.tuning.F = rst.F, s.tuning.G = rst.G, s.tuning.H = rst.H;
  s.tuning.nF = static_cast<std::uint8_t>(rst.nF), s.tuning.nG = static_cast<std::uint8_t>(rst.nG);
  s.tuning.nH = static_cast<std::uint8_t>(rst.nH);
  s.tuning.valve_limit_v = p.valve_limit_v();
  // pp-traj's settings whichever law runs: they are points whatever the law
  s.tuning.set_writable(p.dead_zone(), p.lc_v(), tuning_.traj.trajectory_config(), core::SensorCalibration{config_.mm_per_volt});
  ch_.snapshot.publish(s);
}

void ScanCycle::run(const std::atomic<bool>& stop) noexcept {
  std::int64_t deadline = clock_.now_ns() + period_ns_;
  std::int64_t previous_wake = -1;
  while (!stop.load(std::memory_order_relaxed)) {
    clock_.sleep_until(deadline);
    const std::int64_t wake = clock_.now_ns();
    stats_.wake.add(wake - deadline);
    if (previous_wake >= 0) stats_.jitter.add(std::abs((wake - previous_wake) - period_ns_));
    previous_wake = wake;
    cycle(wake);
    const std::int64_t done = clock_.now_ns();
    stats_.compute.add(done - wake);
    deadline += period_ns_;
    const bool missed = done > deadline;
    detector_.count_deadline(missed);
    if (missed) {  // missed the next deadline: skip the lost periods, count an overrun
      ++stats_.overruns;
      while (deadline < done) deadline += period_ns_;
    }
  }
  shut_down();
}

void ScanCycle::shut_down() noexcept {
  if (moves_.active()) finish_move(MoveEnd::kStopped);
  if (mode_ == Mode::kExcite) end_excitation(ExcitationEnd::kStopped);
  valve_v_ = config_.safe_valve_v;
  daq_.write_valve(valve_v_);
  if (mode_ != Mode::kFault) mode_ = Mode::kStop;
  publish(/*full_stats=*/true);  // the last word: exact statistics, not up to 200 cycles old
}

}  // namespace epa::runtime
