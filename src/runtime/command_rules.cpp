#include "runtime/command_rules.hpp"

#include <cmath>

#include "runtime/axis_words.hpp"

namespace epa::runtime {

CommandRefusal check_command(const Command& c, Mode mode, double position_mm, const ExcitationSettings& excitation,
                             std::uint16_t control_word, const RuntimeConfig& config) noexcept {
  switch (c.kind) {
    case CommandKind::kSetpoint:
      return c.value >= config.setpoint_min_mm && c.value <= config.setpoint_max_mm ? CommandRefusal::kNone
                                                                                  : CommandRefusal::kSetpointOutOfRange;
    case CommandKind::kMode:
      if (c.mode == Mode::kFault) return CommandRefusal::kModeNotSettable;
      if (mode == Mode::kFault) return CommandRefusal::kFaultLatched;
      if (c.mode == Mode::kExcite && mode != Mode::kExcite) {
        // An experiment starts at rest, without a controller's history to take over from.
        if (mode != Mode::kStop) return CommandRefusal::kNotStopped;
        if (!excitation_may_start_at(position_mm, excitation, config)) return CommandRefusal::kOutsideExcitationGuard;
      }
      return CommandRefusal::kNone;
    case CommandKind::kManualValve:
      if (!(std::abs(c.value) <= config.manual_valve_limit_v)) return CommandRefusal::kManualValveOutOfRange;
      return mode == Mode::kManual ? CommandRefusal::kNone : CommandRefusal::kNotManual;
    case CommandKind::kRecord:
      return c.value > 0.0 && std::isfinite(c.value) ? CommandRefusal::kNone : CommandRefusal::kRecordOutOfRange;
    case CommandKind::kExcitation:  // taken in any mode: a running experiment keeps its own settings
      return excitation_problem(c.excitation, config) ? CommandRefusal::kExcitationInvalid : CommandRefusal::kNone;
    case CommandKind::kControl: {
      const std::uint16_t rising = c.control_word & static_cast<std::uint16_t>(~control_word);
      if ((rising & kControlStart) && mode != Mode::kRun) return CommandRefusal::kStartNotRunning;
      if ((rising & kControlStart) && !(c.value >= config.setpoint_min_mm && c.value <= config.setpoint_max_mm))
        return CommandRefusal::kSetpointOutOfRange;
      if ((rising & (kControlJogPlus | kControlJogMinus)) && mode != Mode::kManual) return CommandRefusal::kJogNotManual;
      return CommandRefusal::kNone;  // halt, reset, releases: any time
    }
    case CommandKind::kController:
    case CommandKind::kTuning:  // validated whole by runtime::make_tuning before it is queued
    case CommandKind::kReset:   // a reset without a latched fault does nothing, and that is fine
    case CommandKind::kHeartbeat:
      return CommandRefusal::kNone;
  }
  return CommandRefusal::kNone;
}

std::string_view describe(CommandRefusal r) {
  switch (r) {
    case CommandRefusal::kNone: return "accepted";
    case CommandRefusal::kSetpointOutOfRange: return "the setpoint is outside the configured setpoint range";
    case CommandRefusal::kManualValveOutOfRange: return "the manual valve command is beyond the manual valve limit";
    case CommandRefusal::kNotManual: return "the manual valve command is only taken in MANUAL";
    case CommandRefusal::kFaultLatched: return "a fault is latched: reset it before changing the mode";
    case CommandRefusal::kModeNotSettable: return "FAULT is entered by faults only";
    case CommandRefusal::kRecordQueueFull: return "the recorder has not caught up with earlier requests";
    case CommandRefusal::kRecordOutOfRange: return "the seconds to record must be positive";
    case CommandRefusal::kNotStopped: return "EXCITE is entered from STOP only";
    case CommandRefusal::kOutsideExcitationGuard:
      return "EXCITE starts only with the piston between the excitation's guard lines (guard_mm inside the soft limits): move it there first";
    case CommandRefusal::kExcitationInvalid: return "the excitation settings do not validate together";
    case CommandRefusal::kControllerUnavailable:
      return "pp-traj needs a model that integrates (valve opening -> speed) with a positive gain: the tuning set's model is not one";
    case CommandRefusal::kStartNotRunning: return "a start needs mode RUN: enable the axis first";
    case CommandRefusal::kJogNotManual: return "jogging is only possible in MANUAL";
  }
  return "unknown";
}

}  // namespace epa::runtime
