#pragma once
// POST bodies of the command endpoints, checked by the rules the Modbus handler applies to the
// same points: setpoint within [setpoint_min_mm, setpoint_max_mm], a mode change refused while a
// fault is latched. The result is an HTTP status, an error message, or the commands to queue
// with what the audit trail records for them.
#include <string>
#include <vector>

#include "runtime/command.hpp"
#include "runtime/runtime_config.hpp"
#include "runtime/snapshot.hpp"

namespace epa::web {

enum class CommandEndpoint { kSetpoint, kMode, kReset };

struct AuditedChange {
  std::string point;
  double old_value = 0, new_value = 0;
};

struct CommandDecision {
  int status = 200;     // 400 malformed / out of range, 409 refused in this state
  std::string error;    // set when status != 200
  std::vector<runtime::Command> commands;
  std::vector<AuditedChange> changes;
};

CommandDecision validate_command(CommandEndpoint endpoint, const std::string& body, const runtime::Snapshot& snap,
                                 const runtime::RuntimeConfig& limits);

}  // namespace epa::web
