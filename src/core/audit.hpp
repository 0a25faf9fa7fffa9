#pragma once
// Every accepted change to the appliance (Modbus write, web command, command line) is handed to
// an AuditSink as one group: who changed which points from what to what, and when. The store
// (SQLite) keeps them append-only and applies the persisted ones; its counters tell clients
// how many accepted changes are on disk.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/format.hpp"

namespace epa::core {

// Wall-clock time as audit entries, run history and the store keep it: unix milliseconds.
inline std::int64_t unix_time_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

struct AuditEntry {
  std::int64_t unix_time_ms = 0;
  std::string source;  // "modbus 127.0.0.1:50312", "web 127.0.0.1", "cli"
  std::string point;   // register map point name
  double old_value = 0.0;
  double new_value = 0.0;
};

// An entry with no value on either side (NaN, NULL in the store) is an event an interface
// recorded, not a change: a refused unlock key names the point it was written to, nothing changed.
inline bool is_audit_event(const AuditEntry& e) { return std::isnan(e.old_value) && std::isnan(e.new_value); }

// A value of an entry as people read it: "none" for one there was not (no running tuning set
// before the first).
inline std::string audit_value_text(double v) { return std::isnan(v) ? std::string("none") : format_number(v); }

// How an entry reads in the log, after its source: "set mode from 1 to 0", or for an event
// "(unlock: nothing changed)".
inline std::string audit_text(const AuditEntry& e) {
  if (is_audit_event(e)) return "(" + e.point + ": nothing changed)";
  return "set " + e.point + " from " + audit_value_text(e.old_value) + " to " + audit_value_text(e.new_value);
}

// Accepted changes since start, and how many of them are durable (on disk). A client that
// reads saved >= the accepted count it saw after its write knows its write survives a crash.
struct ChangeCounters {
  std::uint64_t accepted = 0;
  std::uint64_t saved = 0;
  bool saving = true;     // false while writes to disk fail (disk full, read-only): saved stands still
  bool disk_low = false;  // the store's disk has less free space than configured: run files stop, look now
};

// The audit log keeps at least its newest this many rows whatever the retention says (the store's
// trigger refuses to delete them), so a misconfigured retention cannot erase the recent trail.
inline constexpr std::int64_t kAuditMinRows = 1000;

class AuditSink {
 public:
  virtual ~AuditSink() = default;
  // One accepted change: the entries of one request, applied together. Called from I/O threads,
  // so it must not block for long (the store queues it).
  virtual void record(const std::vector<AuditEntry>& change) = 0;
  virtual ChangeCounters counters() const { return {}; }  // a sink that keeps nothing saves nothing
};

}  // namespace epa::core
