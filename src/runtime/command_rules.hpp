#pragma once
// What the scan cycle accepts, written once. The loop checks every command with it at the start of
// a cycle; the write gate (points::WriteGate) checks the commands it builds with it against the
// state it last saw. So a command the gate accepted is refused by the loop only for a reason that
// arose after the gate looked (a fault latched in between, the recorder still busy), and such a
// refusal goes back to the gate through LoopChannels::refusals to be logged and audited.
#include <cstdint>
#include <string_view>

#include "runtime/command.hpp"
#include "runtime/mode.hpp"
#include "runtime/runtime_config.hpp"

namespace epa::runtime {

// Numeric values are part of the Modbus interface (last_command_refusal): append, never renumber.
enum class CommandRefusal : std::uint8_t {
  kNone = 0,
  kSetpointOutOfRange = 1,     // outside [setpoint_min_mm, setpoint_max_mm], or not finite
  kManualValveOutOfRange = 2,  // beyond +-manual_valve_limit_v, or not finite
  kNotManual = 3,              // a manual valve command outside MANUAL
  kFaultLatched = 4,           // a mode change while a fault is latched: reset it first
  kModeNotSettable = 5,        // FAULT is entered by faults only
  kRecordQueueFull = 6,        // the recorder has not caught up with earlier requests
  kRecordOutOfRange = 7,       // record seconds not positive or not finite
  kNotStopped = 8,             // EXCITE is entered from STOP only
  kOutsideExcitationGuard = 9, // EXCITE with the piston outside the excitation's guard lines
  kExcitationInvalid = 10,     // excitation settings that do not validate together (excitation_problem)
  kControllerUnavailable = 11, // pp-traj on a tuning set whose model it cannot use (the loop's own check)
  kStartNotRunning = 12,       // a start (control word) outside RUN: enable the axis first
  kJogNotManual = 13,          // a jog (control word) outside MANUAL
};

// The state-dependent and range rules for one command in mode `mode` with the piston at
// `position_mm` (the last reading). `excitation` holds the settings EXCITE would start with;
// `control_word` the control word before `c` (a control command's rules are for its rising edges).
// kRecordQueueFull is the loop's own (only it sees the recorder's queue). noexcept and
// allocation-free: the loop calls it.
CommandRefusal check_command(const Command& c, Mode mode, double position_mm, const ExcitationSettings& excitation,
                             std::uint16_t control_word, const RuntimeConfig& config) noexcept;

std::string_view describe(CommandRefusal r);  // for logs, the audit trail and HTTP answers

// A command the loop refused: the producer's sequence number (Command::sequence) and why.
struct CommandOutcome {
  std::uint64_t sequence = 0;
  CommandRefusal refusal = CommandRefusal::kNone;
};

}  // namespace epa::runtime
