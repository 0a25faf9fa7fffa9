#include "points/write_gate.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/format.hpp"
#include "points/point_catalog.hpp"
#include "points/tuning_values.hpp"
#include "runtime/tuning.hpp"

namespace epa::points {

struct WriteGate::Decision {
  std::vector<runtime::Command> commands;
  std::vector<PointId> command_point;  // the point each command came from (a tuning command: the first tuning point)
  control::ControllerConfig tuning;
  bool tuning_changed = false;
  runtime::ExcitationSettings excitation;
  bool excitation_changed = false;  // then the excitation command is the group's first
  std::uint16_t control_word = 0;
  int record_select = 0;
  PositionRecords records;
};

namespace {

GateResult refuse(Refusal r, std::string reason) { return {r, std::move(reason)}; }

std::string quoted(PointId id) { return "'" + std::string(name(id)) + "'"; }

// The unlock-protected points that set the next excitation experiment rather than the control law.
bool excitation_point(PointId id) {
  return id == PointId::kExciteSeed || id == PointId::kExciteAmplitudeMin || id == PointId::kExciteAmplitudeMax ||
         id == PointId::kExciteDuration;
}

// Which refusals of the loop's rules mean "not in this state" rather than "not this value".
Refusal gate_refusal(runtime::CommandRefusal r) {
  switch (r) {
    case runtime::CommandRefusal::kNotManual:
    case runtime::CommandRefusal::kStartNotRunning:
    case runtime::CommandRefusal::kJogNotManual:
    case runtime::CommandRefusal::kFaultLatched:
    case runtime::CommandRefusal::kRecordQueueFull:
    case runtime::CommandRefusal::kNotStopped:
    case runtime::CommandRefusal::kOutsideExcitationGuard: return Refusal::kConflict;
    default: return Refusal::kInvalidValue;
  }
}

}  // namespace

WriteGate::WriteGate(WriteLimits limits, const runtime::RuntimeConfig& loop_rules, control::ControllerConfig tuning,
                     runtime::LoopChannels& channels, core::AuditSink* audit, const PositionRecords& records)
    : limits_(std::move(limits)),
      loop_rules_(loop_rules),
      sensor_{loop_rules.mm_per_volt},
      channels_(channels),
      audit_(audit),
      tuning_(std::move(tuning)),
      excitation_(loop_rules.excitation),
      records_(records) {}

PositionRecords WriteGate::records() const {
  std::lock_guard lock(mutex_);
  return records_;
}

int WriteGate::record_select() const {
  std::lock_guard lock(mutex_);
  return record_select_;
}

runtime::Snapshot WriteGate::snapshot() const {
  runtime::Snapshot s = channels_.snapshot.read();
  std::lock_guard lock(mutex_);
  return with_unapplied(s);
}

namespace {
// A target the loop has not taken yet: from the write on, nothing may read as done for the old
// one. The move is under way as far as a client can tell.
void target_pending(runtime::AxisView& axis) {
  axis.moving = true;
  // The new motion starts where the piston stands: an error against the old one no longer applies.
  axis.in_position = axis.target_reached = axis.off_target = axis.halted = axis.following_error = false;
}
}  // namespace

runtime::Snapshot WriteGate::with_unapplied(runtime::Snapshot s) const {
  while (!unapplied_.empty() && unapplied_.front().sequence <= s.last_sequence) unapplied_.pop_front();
  bool entering_run = false;  // RUN entered by an unapplied write: a setpoint written with it moves
  for (const runtime::Command& c : unapplied_) {
    switch (c.kind) {
      case runtime::CommandKind::kSetpoint:
        // The loop moves on a setpoint that changes in RUN (scan_cycle.cpp: kSetpoint).
        if (s.mode == runtime::Mode::kRun && (c.value != s.setpoint_mm || entering_run)) target_pending(s.axis);
        s.setpoint_mm = c.value;
        break;
      case runtime::CommandKind::kMode:
        if (c.mode == runtime::Mode::kExcite && s.mode != runtime::Mode::kExcite) s.excitation_left_s = s.excitation.duration_s;  // all of it is left
        if (c.mode != s.mode) {
          entering_run = c.mode == runtime::Mode::kRun;
          // The motion bits as the loop will show them in the new mode, not the old one's (a read
          // just after mode := MANUAL showed in_position and halted with manual_mode): nothing is
          // moving, in position or off target yet; RUN and MANUAL start from a hold.
          // target_reached is RUN's alone, and RUN starts without one.
          s.axis.moving = s.axis.in_position = s.axis.target_reached = s.axis.jogging = s.axis.off_target = false;
          if (c.mode == runtime::Mode::kRun || c.mode == runtime::Mode::kManual) s.axis.halted = false;
          if (s.mode == runtime::Mode::kManual || c.mode == runtime::Mode::kManual) s.manual_valve_v = loop_rules_.safe_valve_v;
        }
        s.mode = c.mode;
        break;
      case runtime::CommandKind::kManualValve: s.manual_valve_v = c.value; break;
      case runtime::CommandKind::kController: s.controller = s.running_law = c.controller; break;
      case runtime::CommandKind::kHeartbeat: s.heartbeat = c.heartbeat; break;
      case runtime::CommandKind::kExcitation: s.excitation = c.excitation; break;
      case runtime::CommandKind::kControl: {
        const std::uint16_t rising = c.control_word & ~s.axis.control_word;
        if ((rising & runtime::kControlStart) && s.mode == runtime::Mode::kRun) {
          s.setpoint_mm = c.value;
          s.running_law = c.start_controller ? c.controller : s.controller;  // as the loop will run the move
          target_pending(s.axis);
        }
        if ((rising & runtime::kControlHalt) && s.mode == runtime::Mode::kRun) {
          s.axis.in_position = s.axis.target_reached = false;  // in position after the halt only if it stops within the window
          s.axis.halted = true;
        }
        s.axis.control_word = c.control_word;
        break;
      }
      case runtime::CommandKind::kTuning:  // the gate's copy is what the loop takes
        s.tuning.set_writable(tuning_.dead_zone, tuning_.lc_v, tuning_.trajectory, sensor_);
        break;
      case runtime::CommandKind::kReset:
      case runtime::CommandKind::kRecord: break;
    }
  }
  s.error_mm = s.setpoint_mm - s.position_mm;
  return s;
}

void WriteGate::remember_unapplied(std::span<const runtime::Command> commands) {
  for (const auto& c : commands) unapplied_.push_back(c);
  while (unapplied_.size() > kUnapplied) unapplied_.pop_front();
}

ConfiguredLimits WriteGate::configured_limits() const {
  const PointRange& setpoint = limits_.range(PointId::kSetpoint);
  return {loop_rules_.soft_min_mm, loop_rules_.soft_max_mm, setpoint.min.value, setpoint.max.value,
          loop_rules_.in_position_window_mm, loop_rules_.following_error_mm, loop_rules_.following_error_time_s};
}

control::ControllerConfig WriteGate::running_tuning() const {
  std::lock_guard lock(mutex_);
  return tuning_;
}

runtime::ExcitationSettings WriteGate::excitation_settings() const {
  std::lock_guard lock(mutex_);
  return excitation_;
}

GateResult WriteGate::build(std::span<const PointWrite> writes, const Requester& who, const runtime::Snapshot& snap,
                            const control::ControllerConfig& tuning, const runtime::ExcitationSettings& excitation,
                            Decision& out) const {
  if (writes.empty()) return refuse(Refusal::kInvalidValue, "nothing to write");
  if (GateResult r = check_values(writes); !r.accepted()) return r;
  if (GateResult r = check_rights(writes, who); !r.accepted()) return r;
  // A commissioning or health command goes to its service, not the loop: nothing more to decide here.
  if (std::ranges::any_of(writes, [](const PointWrite& w) { return w.id == PointId::kCommissionCommand || w.id == PointId::kHealthCommand; }))
    return check_service_command(writes);
  // The commands, all of them or none, from the gate's state as it stands.
  out.tuning = tuning;
  out.excitation = excitation;
  out.control_word = control_word_;
  out.record_select = record_select_;
  out.records = records_;
  if (GateResult r = edit_records(writes, out); !r.accepted()) return r;
  if (GateResult r = add_commands(writes, snap, tuning, out); !r.accepted()) return r;
  return check_loop_rules(out, snap, excitation);
}

// Each value: a writable point, within the one set of limits, whole where it must be.
GateResult WriteGate::check_values(std::span<const PointWrite> writes) const {
  for (const PointWrite& w : writes) {
    if (index(w.id) >= kPointCount) return refuse(Refusal::kNotWritable, "unknown point");
    const PointDef& p = point(w.id);
    if (!p.gated()) return refuse(Refusal::kNotWritable, fmt::format("{} is read-only", quoted(w.id)));
    if (auto e = limits_.check(w.id, w.value); !e.empty()) return refuse(Refusal::kInvalidValue, e);
    if (p.integer && w.value != std::floor(w.value))
      return refuse(Refusal::kInvalidValue, fmt::format("{} takes whole numbers, not {}", quoted(w.id), core::format_number(w.value)));
  }
  return {};
}

// The client's rights: to write at all, and to write tuning.
GateResult WriteGate::check_rights(std::span<const PointWrite> writes, const Requester& who) {
  if (!who.may_write) return refuse(Refusal::kForbidden, who.no_write_reason.empty() ? "this client may not write" : who.no_write_reason);
  for (const PointWrite& w : writes)
    if (point(w.id).tuning() && !who.tuning_unlocked)
      return refuse(Refusal::kForbidden, fmt::format("{} is a tuning point: {}", quoted(w.id),
                                                     who.tuning_locked_reason.empty() ? "unlock the tuning first" : who.tuning_locked_reason));
  return {};
}

// A service's command (commissioning, model health) is written alone, and only to a gate with the
// service behind it.
GateResult WriteGate::check_service_command(std::span<const PointWrite> writes) const {
  const auto service = std::ranges::find_if(writes, [](const PointWrite& w) { return w.id == PointId::kCommissionCommand || w.id == PointId::kHealthCommand; });
  const std::string point = quoted(service->id);
  if (writes.size() > 1) return refuse(Refusal::kInvalidValue, fmt::format("{} is written alone", point));
  if (service->id == PointId::kCommissionCommand && !commission_)
    return refuse(Refusal::kNotWritable, fmt::format("{}: this appliance runs no commissioning service", point));
  if (service->id == PointId::kHealthCommand && !health_)
    return refuse(Refusal::kNotWritable, fmt::format("{}: this appliance runs no model-health monitor", point));
  return {};
}

// The record a start takes may come in the same group: selections and record edits first.
GateResult WriteGate::edit_records(std::span<const PointWrite> writes, Decision& out) const {
  for (const PointWrite& w : writes) {
    if (w.id == PointId::kRecordSelect) out.record_select = static_cast<int>(w.value);
    RecordField f;
    if (!record_field(w.id, f)) continue;
    if (f.kind == RecordField::kTarget && !(w.value >= loop_rules_.setpoint_min_mm && w.value <= loop_rules_.setpoint_max_mm))
      return refuse(Refusal::kInvalidValue,
                    fmt::format("{} {} mm is outside the setpoint range [{}, {}] mm", quoted(w.id), core::format_number(w.value),
                                core::format_number(loop_rules_.setpoint_min_mm), core::format_number(loop_rules_.setpoint_max_mm)));
    if (f.kind == RecordField::kController && w.value != kKeepController && !(w.value >= 0 && w.value <= 3))
      return refuse(Refusal::kInvalidValue, fmt::format("{} takes 0 pp, 1 pp-ngidz, 2 pp-ffidz, 3 pp-traj or 255 (the running law), not {}",
                                                        quoted(w.id), core::format_number(w.value)));
    set_record_value(out.records[f.record], f.kind, w.value);
  }
  return {};
}

// The control word `word` as a command; a start edge resolves the selected record (or the
// setpoint, written in this group or standing) into the move it commands.
runtime::Command WriteGate::control_command(std::uint16_t word, std::span<const PointWrite> writes, const runtime::Snapshot& snap,
                                            Decision& out) {
  runtime::Command c = runtime::control_command(word);
  const std::uint16_t rising = word & static_cast<std::uint16_t>(~out.control_word);
  out.control_word = word;
  if (!(rising & runtime::kControlStart)) return c;
  if (out.record_select == 0) {
    c.value = snap.setpoint_mm;
    for (const PointWrite& w : writes)
      if (w.id == PointId::kSetpoint) c.value = w.value;
    return c;
  }
  const PositionRecord& r = out.records[static_cast<std::size_t>(out.record_select - 1)];
  c.value = r.target_mm;
  c.speed_limit_mm_s = r.speed_mm_s;
  c.window_mm = r.window_mm;
  c.approach_direction = approach_direction(r.approach);
  if (r.controller != kKeepController) {
    c.start_controller = true;
    c.controller = static_cast<control::ControllerKind>(r.controller);
  }
  return c;
}

// The command one write stands for, in `c`; refused when the point has none behind it. `tuning`
// is the running tuning before the group's own tuning writes.
GateResult WriteGate::command_for(const PointWrite& w, std::span<const PointWrite> writes, const runtime::Snapshot& snap,
                                  const control::ControllerConfig& tuning, Decision& out, runtime::Command& c) const {
  switch (w.id) {
    case PointId::kSetpoint: c = runtime::setpoint_command(w.value); break;
    case PointId::kMode: c = runtime::mode_command(static_cast<runtime::Mode>(static_cast<int>(w.value))); break;
    case PointId::kController:
      c = runtime::controller_command(static_cast<control::ControllerKind>(static_cast<int>(w.value)));
      if (c.controller == control::ControllerKind::kPpTraj) {  // said here, not only by the loop after the answer
        control::ControllerConfig traj = tuning;
        traj.kind = control::ControllerKind::kPpTraj;
        if (auto p = control::ControllerParams::make(traj); !p) return refuse(Refusal::kInvalidValue, fmt::format("{}: {}", quoted(w.id), p.error().message));
      }
      break;
    case PointId::kManualValve: c = runtime::manual_valve_command(w.value); break;
    case PointId::kReset: c = runtime::reset_command(); break;
    case PointId::kHeartbeat: c = runtime::heartbeat_command(static_cast<std::uint32_t>(w.value)); break;
    case PointId::kRecord: c = runtime::record_command(w.value); break;
    case PointId::kControlWord: c = control_command(static_cast<std::uint16_t>(w.value), writes, snap, out); break;
    case PointId::kExciteSeed: out.excitation.seed = static_cast<std::uint32_t>(w.value); break;
    case PointId::kExciteAmplitudeMin: out.excitation.amplitude_min_v = w.value; break;
    case PointId::kExciteAmplitudeMax: out.excitation.amplitude_max_v = w.value; break;
    case PointId::kExciteDuration: out.excitation.duration_s = w.value; break;
    default: {
      const int bit = control_bit(w.id);
      if (bit < 0) return refuse(Refusal::kNotWritable, fmt::format("{} has no command behind it", quoted(w.id)));
      const auto mask = static_cast<std::uint16_t>(1u << bit);
      c = control_command(static_cast<std::uint16_t>(w.value != 0.0 ? out.control_word | mask : out.control_word & ~mask), writes, snap, out);
      break;
    }
  }
  return {};
}

// Each write's command, in the order the loop is to apply them: the excitation settings first,
// then a mode change, the rest as written, the tuning last.
GateResult WriteGate::add_commands(std::span<const PointWrite> writes, const runtime::Snapshot& snap,
                                   const control::ControllerConfig& tuning, Decision& out) const {
  PointId first_tuning_point = PointId::kCount, first_excitation_point = PointId::kCount;
  for (const PointWrite& w : writes) {
    if (w.id == PointId::kRecordSelect) continue;      // the gate's own: taken by edit_records
    if (RecordField f; record_field(w.id, f)) continue;  // the same
    if (set_tuning_value(out.tuning, w.id, w.value, sensor_)) {
      if (first_tuning_point == PointId::kCount) first_tuning_point = w.id;
      continue;
    }
    runtime::Command c;
    if (GateResult r = command_for(w, writes, snap, tuning, out, c); !r.accepted()) return r;
    if (excitation_point(w.id)) {
      if (first_excitation_point == PointId::kCount) first_excitation_point = w.id;
      continue;
    }
    out.commands.push_back(c);
    out.command_point.push_back(w.id);
  }
  move_mode_first(out);
  if (first_tuning_point != PointId::kCount) {
    // Every tuning point of the group becomes one tuning command, validated whole (e.g. b_l > b_r
    // after this write is refused), last in the group.
    auto t = runtime::make_tuning(out.tuning);
    if (!t) return refuse(Refusal::kInvalidValue, fmt::format("the tuning would not validate: {}", t.error().message));
    // The loop does not take a set that the selected pp-traj cannot run on (kControllerUnavailable):
    // said here, before the answer, with the law's own reason.
    control::ControllerKind law = snap.controller;
    for (const runtime::Command& c : out.commands)
      if (c.kind == runtime::CommandKind::kController) law = c.controller;
    if (law == control::ControllerKind::kPpTraj && !t->traj_available) {
      control::ControllerConfig traj = out.tuning;
      traj.kind = control::ControllerKind::kPpTraj;
      const auto p = control::ControllerParams::make(traj);
      return refuse(Refusal::kInvalidValue, fmt::format("pp-traj runs and could not run on this tuning: {}", p ? "" : p.error().message));
    }
    out.tuning_changed = true;
    out.commands.push_back(runtime::tuning_command(*t));
    out.command_point.push_back(first_tuning_point);
  }
  if (first_excitation_point != PointId::kCount) {
    // Every excitation point of the group becomes one command, validated whole (e.g. a minimum
    // above the maximum is refused), first in the group, so "settings and mode excite" in one
    // write starts the experiment with the new settings.
    if (const char* problem = runtime::excitation_problem(out.excitation, loop_rules_))
      return refuse(Refusal::kInvalidValue, fmt::format("the excitation settings would not validate: {}", problem));
    out.excitation_changed = true;
    out.commands.insert(out.commands.begin(), runtime::excitation_command(out.excitation));
    out.command_point.insert(out.command_point.begin(), first_excitation_point);
  }
  return {};
}

// A mode change goes first, so "enable and start" (or enable and a setpoint) in one write moves
// the axis: RUN entered holds, and the move comes after.
void WriteGate::move_mode_first(Decision& out) {
  for (std::size_t i = 1; i < out.commands.size(); ++i)
    if (out.commands[i].kind == runtime::CommandKind::kMode) {
      const auto at = static_cast<std::ptrdiff_t>(i);
      std::rotate(out.commands.begin(), out.commands.begin() + at, out.commands.begin() + at + 1);
      std::rotate(out.command_point.begin(), out.command_point.begin() + at, out.command_point.begin() + at + 1);
    }
}

// The scan cycle's own rules, in the state it last published, carried through the group in the
// order the loop applies it (mode MANUAL then a manual valve command is one valid group).
GateResult WriteGate::check_loop_rules(const Decision& d, const runtime::Snapshot& snap, const runtime::ExcitationSettings& excitation) const {
  runtime::Mode mode = snap.mode;
  runtime::ExcitationSettings next_excitation = excitation;
  std::uint16_t word = control_word_;
  for (std::size_t i = 0; i < d.commands.size(); ++i) {
    const runtime::Command& c = d.commands[i];
    if (const auto r = runtime::check_command(c, mode, snap.position_mm, next_excitation, word, loop_rules_); r != runtime::CommandRefusal::kNone)
      return refuse(gate_refusal(r), fmt::format("{}: {}", quoted(d.command_point[i]), runtime::describe(r)));
    if (c.kind == runtime::CommandKind::kControl) word = c.control_word;
    if (c.kind == runtime::CommandKind::kMode) mode = c.mode;
    if (c.kind == runtime::CommandKind::kExcitation) next_excitation = c.excitation;
    if (c.kind == runtime::CommandKind::kReset && mode == runtime::Mode::kFault) mode = runtime::Mode::kStop;
  }
  return {};
}

GateResult WriteGate::decide(std::span<const PointWrite> writes, const Requester& who, const runtime::Snapshot& snap,
                             std::vector<runtime::Command>* commands) const {
  Decision d;
  const auto tuning = running_tuning();
  GateResult r = build(writes, who, snap, tuning, excitation_settings(), d);
  if (r.accepted() && commands) *commands = d.commands;
  return r;
}

GateResult WriteGate::submit(std::span<const PointWrite> writes, const Requester& who) {
  if (!writes.empty() && writes.front().id == PointId::kCommissionCommand) return commission(writes, who);
  if (!writes.empty() && writes.front().id == PointId::kHealthCommand) return health(writes, who);
  std::lock_guard lock(mutex_);
  const runtime::Snapshot snap = with_unapplied(channels_.snapshot.read());  // decided on what reads show
  Decision d;
  if (GateResult r = build(writes, who, snap, tuning_, excitation_, d); !r.accepted()) return r;
  // One recording at a time, paced: each is a file on disk, and a client's loop of record writes
  // must not fill it (the recorder's quota is the second bound).
  const auto now = std::chrono::steady_clock::now();
  const bool records = std::ranges::any_of(d.commands, [](const runtime::Command& c) { return c.kind == runtime::CommandKind::kRecord; });
  if (records && last_record_request_ != std::chrono::steady_clock::time_point{} &&
      now - last_record_request_ < std::chrono::duration<double>(loop_rules_.record_min_interval_s))
    return refuse(Refusal::kConflict, quoted(PointId::kRecord) + ": a recording was asked for less than " +
                                          core::format_number(loop_rules_.record_min_interval_s) + " s ago: one at a time");
  const PositionRecords records_before = records_;  // the audit trail's old values
  const int record_select_before = record_select_;
  const std::uint64_t first = next_sequence_;
  for (std::size_t i = 0; i < d.commands.size(); ++i) d.commands[i].sequence = first + i;
  if (!d.commands.empty() && !channels_.commands.try_push_all(d.commands.data(), d.commands.size()))
    return refuse(Refusal::kBusy, "the scan cycle's command queue is full: try again");
  next_sequence_ += d.commands.size();
  if (records) last_record_request_ = now;
  if (d.tuning_changed) tuning_ = d.tuning;
  if (d.excitation_changed) excitation_ = d.excitation;
  control_word_ = d.control_word;
  record_select_ = d.record_select;
  records_ = d.records;
  remember_unapplied(d.commands);

  // Accepted: the audit trail (and so the store) gets the group. Each entry keeps its command's
  // sequence number while it is in flight, so a late refusal can be audited against it.
  InterfaceStatus status;
  status.records = records_before;
  status.record_select = record_select_before;
  const PointContext ctx{snap, status};
  const std::int64_t time_ms = core::unix_time_ms();
  std::vector<core::AuditEntry> change;
  for (const PointWrite& w : writes) {
    const PointDef& p = point(w.id);
    if (!p.audited) continue;
    core::AuditEntry e{time_ms, who.source, std::string(p.name), p.value(ctx), w.value};
    // The control word (or a bit of it) written again as it was is a held jog's keep-alive, several
    // a second: no change, so not in the audit trail and the store.
    const bool control = w.id == PointId::kControlWord || control_bit(w.id) >= 0;
    if (control && e.old_value == e.new_value) continue;
    std::uint64_t sequence = first + d.commands.size() - 1;  // a tuning point: the tuning command, last
    if (excitation_point(w.id)) sequence = first;            // an excitation point: the excitation command, first
    for (std::size_t i = 0; i < d.commands.size() && !p.tuning(); ++i)
      if (d.command_point[i] == w.id) sequence = first + i;
    in_flight_.push_back({sequence, e});
    if (in_flight_.size() > kInFlight) in_flight_.pop_front();
    change.push_back(std::move(e));
  }
  if (audit_ && !change.empty()) audit_->record(change);
  return {};
}

GateResult WriteGate::commission(std::span<const PointWrite> writes, const Requester& who) {
  {
    std::lock_guard lock(mutex_);
    Decision d;
    if (GateResult r = build(writes, who, channels_.snapshot.read(), tuning_, excitation_, d); !r.accepted()) return r;
  }
  // The service is called outside the gate's lock: its sequence writes through this gate.
  const double value = writes.front().value;
  if (value == 1.0) {
    const auto started = commission_->start("", who.source);
    if (started.result == CommissionStart::kBusy) return refuse(Refusal::kConflict, "commission_command: " + started.message);
    if (started.result == CommissionStart::kBadSpec) return refuse(Refusal::kInvalidValue, "commission_command: " + started.message);
  } else if (!commission_->abort(who.source)) {
    return refuse(Refusal::kConflict, "commission_command: no commissioning run is under way");
  }
  return {};  // audited by the service, under who.source, as a start or abort from any interface
}

GateResult WriteGate::health(std::span<const PointWrite> writes, const Requester& who) {
  {
    std::lock_guard lock(mutex_);
    Decision d;
    if (GateResult r = build(writes, who, channels_.snapshot.read(), tuning_, excitation_, d); !r.accepted()) return r;
  }
  health_->retake_baseline(who.source);  // audited by the monitor, under who.source
  return {};
}

HealthReport WriteGate::health_report(bool with_trend) const {
  if (health_) return health_->report(with_trend);
  HealthReport r;
  r.reason = "this appliance runs no model-health monitor";
  return r;
}

GateResult WriteGate::replace_tuning(const control::ControllerConfig& replacement, const Requester& who, const core::AuditEntry& entry) {
  if (!who.may_write) return refuse(Refusal::kForbidden, who.no_write_reason);
  if (!who.tuning_unlocked) return refuse(Refusal::kForbidden, "a tuning set is tuning: unlock the tuning first");
  const control::ControllerConfig tuning = runtime::with_loop_limits(replacement, loop_rules_);
  auto t = runtime::make_tuning(tuning);
  if (!t) return refuse(Refusal::kInvalidValue, "the tuning set would not validate: " + t.error().message);
  std::lock_guard lock(mutex_);
  const control::ControllerKind running = with_unapplied(channels_.snapshot.read()).controller;
  runtime::Command commands[] = {runtime::tuning_command(*t), runtime::controller_command(tuning.kind)};
  for (auto& c : commands) c.sequence = next_sequence_++;
  if (!channels_.commands.try_push_all(commands, std::size(commands)))
    return refuse(Refusal::kBusy, "the scan cycle's command queue is full: try again");
  tuning_ = tuning;
  remember_unapplied(commands);
  // Every change of the running law is in the audit trail, whoever made it: here the set's law.
  std::vector<core::AuditEntry> entries{entry};
  if (tuning.kind != running)
    entries.push_back({entry.unix_time_ms, entry.source, std::string(name(PointId::kController)), static_cast<double>(running),
                       static_cast<double>(tuning.kind)});
  if (audit_) audit_->record(entries);
  return {};
}

void WriteGate::take_refusals(const std::function<void(const std::string&)>& log) {
  runtime::CommandOutcome o;
  while (channels_.refusals.try_pop(o)) {
    std::vector<core::AuditEntry> refused;
    {
      std::lock_guard lock(mutex_);
      for (const InFlight& f : in_flight_) {
        if (f.sequence != o.sequence) continue;
        // The point kept its value: audited as a change from the refused value back to it.
        refused.push_back({core::unix_time_ms(), "scan cycle, refusing " + f.entry.source + ": " + std::string(runtime::describe(o.refusal)),
                           f.entry.point, f.entry.new_value, f.entry.old_value});
      }
    }
    if (log) {
      if (refused.empty()) log("scan cycle refused command " + std::to_string(o.sequence) + ": " + std::string(runtime::describe(o.refusal)));
      for (const auto& e : refused)
        log("scan cycle refused " + e.point + " = " + core::format_number(e.old_value) + " (" + e.source + ")");
    }
    if (audit_ && !refused.empty()) audit_->record(refused);
  }
}

}  // namespace epa::points
