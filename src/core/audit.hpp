#pragma once
// Every accepted change to the appliance (Modbus write, web command, command line) is handed to
// an AuditSink: who changed which point from what to what, and when. The store (SQLite) keeps
// them append-only; until it is configured, the log does.
#include <cstdint>
#include <string>

namespace epa::core {

struct AuditEntry {
  std::int64_t unix_time_ms = 0;
  std::string source;  // "modbus 127.0.0.1:50312", "web", "cli"
  std::string point;   // register map point name
  double old_value = 0.0;
  double new_value = 0.0;
};

class AuditSink {
 public:
  virtual ~AuditSink() = default;
  virtual void record(const AuditEntry& entry) = 0;  // must not block for long: called from I/O threads
};

}  // namespace epa::core
