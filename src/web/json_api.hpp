#pragma once
// The JSON bodies of the read-only API, built from the published snapshot and the web thread's
// own buffers. Numbers that mean "never" / "no value" (NaN) are written as null.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/audit.hpp"
#include "points/health_control.hpp"
#include "points/position_records.hpp"
#include "points/write_limits.hpp"
#include "runtime/fault_history.hpp"
#include "runtime/snapshot.hpp"
#include "web/trend_buffer.hpp"

namespace epa::web {

// What the Modbus server reports about itself (enabled = false when it is not running).
struct ModbusStats {
  bool enabled = false;
  int clients = 0;
  std::uint64_t requests = 0, exceptions = 0;
  bool any_address_may_command = false;  // writable with no [modbus] write_clients: anyone on the network may move the axis
};

// What the tuning store reports (enabled = false when the appliance runs without one).
struct StoreStats {
  bool enabled = false;
  bool ok = true;                // the last write succeeded
  std::uint64_t accepted = 0;    // accepted changes since start
  std::uint64_t saved = 0;       // ... of which on disk
  std::string last_error;        // of the last failed write
  std::string tuning_set;        // the running set's name
  bool disk_low = false;         // free space below [store] min_free_mb: run files stop, the store may be next
};

// With the status word as "status_word" and bit by bit in "status_bits" (ready, run_enabled, ...:
// the bits' point names), the control word as the loop applied it, and the model-health verdict
// as "health": {"state", "effect", "size", "ratio", "moves_since_onset", "moves_seen", "value",
// "commissioned", "unit", "reason"} (effect, size, unit "" and the numbers null when they do not apply).
// The client's certificate, over HTTPS: who the request's client is and what its role may do.
struct CertificateLogin {
  std::string subject;  // "/CN=eng"
  std::string role;     // "engineer"; "" when it names none
  std::string rights;   // "read", "operate" or "tune"; "" when the role is not in the table
};

// With "client_certificate": {"subject", "role", "rights"} of `login`, null without one.
std::string status_json(const runtime::Snapshot& s, const ModbusStats& modbus, bool commands_enabled,
                        const StoreStats& store = {}, const points::HealthReport& health = {},
                        const std::optional<CertificateLogin>& login = std::nullopt);
// The model-health verdict as in /api/status, with its gaps, the moves not judged and "trend":
// the newest judgements, oldest first, each {"move", "estimates": [{"effect", "ratio", "reduction"}]}.
std::string health_json(const points::HealthReport& health);
std::string trend_json(const std::vector<TrendPoint>& points, const runtime::Snapshot& s);
std::string moves_json(const std::vector<MoveRecord>& moves);
std::string tuning_json(const runtime::Snapshot& s);
std::string audit_json(const std::vector<core::AuditEntry>& entries);
// The fault history: {"count": faults recorded, "faults": [newest first]}, each with its time as
// ISO 8601 UTC and unix ms, code and name, text, the mode it was in and the position, setpoint,
// valve and sensor values then (null: not known). `dropped` (when given): faults the loop's event
// ring had no room for, missing from the history.
std::string faults_json(std::uint64_t count, const std::vector<runtime::FaultRecord>& newest_first,
                        std::optional<std::uint64_t> dropped = std::nullopt);
// The point catalog with each writable point's range as the write gate applies it.
std::string points_json(const points::WriteLimits& limits);
// A record's keys in /api/records (GET and POST) and `epa records`: the HTTP format's own, written
// here once (they are not point names, though two of them spell like one: speed_mm_s, controller).
struct RecordKeys {
  static constexpr const char* kRecord = "record";
  static constexpr const char* kTarget = "target_mm";
  static constexpr const char* kSpeed = "speed_mm_s";
  static constexpr const char* kWindow = "window_mm";
  static constexpr const char* kController = "controller";
  static constexpr const char* kApproach = "approach";
};

// The position-record table: {"records": [{"record": 1..32, "target_mm", "speed_mm_s" (0: no limit),
// "window_mm" (0: the configured window), "controller" (a law's name, or "running")}, ...],
// "record_select": the record a start takes (0: the setpoint)}.
std::string records_json(const points::PositionRecords& records, int record_select);
std::string error_json(const std::string& message);

}  // namespace epa::web
