#pragma once
// What other threads ask of the scan cycle. Commands are validated by the write gate
// (points::WriteGate) with the loop's own rules (command_rules.hpp), queued, and applied at the
// start of the next cycle, whole, or refused there for a reason that arose after the gate looked
// (counted as rejected and reported back by sequence number).
#include <cstdint>

#include "control/controller_kind.hpp"
#include "runtime/excitation_settings.hpp"
#include "runtime/mode.hpp"
#include "runtime/tuning.hpp"

namespace epa::runtime {

enum class CommandKind : std::uint8_t {
  kSetpoint,     // value = setpoint, mm
  kMode,         // mode = stop, run, manual or excite (refused while FAULT is latched; excite from STOP only)
  kManualValve,  // value = valve command for MANUAL, V
  kController,   // controller = the law to use from the next cycle on
  kTuning,       // tuning = new parameters for all three laws
  kReset,        // clears a latched fault: FAULT -> STOP
  kHeartbeat,    // heartbeat = the supervising client's counter
  kRecord,       // value = seconds of history to write as a run file
  kExcitation,   // excitation = the settings of the next EXCITE, whole
  kControl,      // control_word = the client's new control word (axis_words.hpp); on a start edge,
                 // value = the target, mm, with speed_limit_mm_s, window_mm and (start_controller) controller
};

struct Command {
  CommandKind kind = CommandKind::kReset;
  double value = 0.0;
  Mode mode = Mode::kStop;
  control::ControllerKind controller = control::ControllerKind::kPpFfidz;
  std::uint32_t heartbeat = 0;
  std::uint16_t control_word = 0;
  double speed_limit_mm_s = 0.0, window_mm = 0.0;  // a start's: 0 none / the configured window
  double approach_direction = 0.0;  // a start's: +1 from below, -1 from above, 0 the near side (control/sliding_approach.hpp)
  bool start_controller = false;                    // a start runs its move with `controller` (that move only)
  std::uint64_t sequence = 0;  // the producer's number for it: a refusal is reported with it
  Tuning tuning;
  ExcitationSettings excitation;
};

inline Command setpoint_command(double mm) { Command c; c.kind = CommandKind::kSetpoint; c.value = mm; return c; }
inline Command mode_command(Mode m) { Command c; c.kind = CommandKind::kMode; c.mode = m; return c; }
inline Command manual_valve_command(double v) { Command c; c.kind = CommandKind::kManualValve; c.value = v; return c; }
inline Command controller_command(control::ControllerKind k) { Command c; c.kind = CommandKind::kController; c.controller = k; return c; }
inline Command tuning_command(const Tuning& t) { Command c; c.kind = CommandKind::kTuning; c.tuning = t; return c; }
inline Command reset_command() { Command c; c.kind = CommandKind::kReset; return c; }
inline Command heartbeat_command(std::uint32_t n) { Command c; c.kind = CommandKind::kHeartbeat; c.heartbeat = n; return c; }
inline Command record_command(double seconds) { Command c; c.kind = CommandKind::kRecord; c.value = seconds; return c; }
inline Command control_command(std::uint16_t word) { Command c; c.kind = CommandKind::kControl; c.control_word = word; return c; }
inline Command excitation_command(const ExcitationSettings& s) { Command c; c.kind = CommandKind::kExcitation; c.excitation = s; return c; }

}  // namespace epa::runtime
