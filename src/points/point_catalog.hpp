#pragma once
// The catalog of points: everything an operator or integrator reads from the appliance (snapshot
// values, tuning, metrics, loop statistics, counters) and the things they write (setpoint, mode,
// controller, manual valve, tuning, excitation settings, reset, heartbeat, record, unlock), each
// with its public name, unit, access, range and description. Every interface reads it: the
// register map binds Modbus addresses to its points, the JSON API and /metrics name values by it,
// the store keys retained points by it, and the write gate checks writes against its access and
// range. `epa registers --points` lists it.
#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "points/commission_control.hpp"
#include "points/health_control.hpp"
#include "points/point_id.hpp"
#include "points/position_records.hpp"
#include "runtime/fault_history.hpp"
#include "runtime/snapshot.hpp"

namespace epa::points {

// The limits and windows an HMI works within, as this appliance runs them: the setpoint range as
// writes are checked (the configuration narrowed by the register map), the rest as configured.
struct ConfiguredLimits {
  double soft_min_mm = 0, soft_max_mm = 0;          // [limits]: outside them in RUN, MANUAL or EXCITE faults
  double setpoint_min_mm = 0, setpoint_max_mm = 0;  // a setpoint or record target outside is refused
  double in_position_window_mm = 0;                 // [motion]: the default in-position window
  double following_error_mm = 0, following_error_time_s = 0;  // [limits]: the following error's limit and time (0: off)
};

// What the interfaces know besides the loop's snapshot, for the points that describe them.
struct InterfaceStatus {
  std::uint32_t change_counter = 0;  // accepted changes since start, every interface
  std::uint32_t saved_counter = 0;   // how many of them are on disk
  bool saving = true;                // the store's writes succeed
  std::uint64_t requests = 0;        // Modbus requests served
  int clients = 0;                   // connected Modbus clients
  bool locked = true;                // tuning points refuse this client's writes
  std::uint64_t unlock_failures = 0; // refused unlock attempts since start (wrong key, back-off)
  CommissionView commission;         // the commissioning service's state (WriteGate::commission_view)
  HealthView health;                 // the model-health monitor's verdict (WriteGate::health_view)
  PositionRecords records{};         // the position-record table (WriteGate::records)
  int record_select = 0;             // the record a start takes (0: the setpoint)
  std::uint64_t fault_history_count = 0;  // faults recorded (LoopChannels::fault_history)
  std::array<runtime::FaultRecord, kFaultHistoryPoints> recent_faults{};  // newest first; code kNone: an empty slot
  ConfiguredLimits limits{};              // what the configuration and the register map allow (WriteGate::configured_limits)
  bool disk_low = false;                  // the store's disk is below [store] min_free_mb
};

// The status word (runtime/axis_words.hpp) of the loop's state and the interfaces' (warning
// includes a store that does not save or whose disk is low: `store_well` false; and the
// model-health monitor's warning, health_warns()).
std::uint16_t status_word(const runtime::Snapshot& s, bool store_well, bool health_warning);
// ... with the interfaces' part read from what they know.
std::uint16_t status_word(const runtime::Snapshot& s, const InterfaceStatus& status);

struct PointContext {
  const runtime::Snapshot& snapshot;
  const InterfaceStatus& status;
};

enum class Access : std::uint8_t {
  kRead,    // read only
  kWrite,   // any client with write rights
  kTuning,  // only while unlocked (Modbus: the key; HTTP: the token)
  kKey,     // the unlock key: taken by the interface that owns the key, never queued to the loop
};

struct PointDef {
  PointId id = PointId::kCount;
  std::string_view name;
  std::string_view unit;
  std::string_view description;
  Access access = Access::kRead;
  double min = 0, max = 0;  // the values a write may carry, before the configuration narrows them
  bool integer = false;     // whole numbers only (enumerations, counters, keys)
  bool audited = true;      // accepted writes go to the audit trail (not: the heartbeat, a keep-alive)
  double (*read)(const PointContext&, int index) = nullptr;
  int index = 0;            // for the coefficients: F3 reads F[3]

  bool writable() const { return access != Access::kRead; }
  bool gated() const { return access == Access::kWrite || access == Access::kTuning; }  // written through the gate
  bool tuning() const { return access == Access::kTuning; }
  double value(const PointContext& c) const { return read(c, index); }
};

std::span<const PointDef> point_catalog();        // in PointId order
const PointDef& point(PointId id);                 // id < kCount
std::string_view name(PointId id);                 // the public name
const PointDef* find_point(std::string_view name);  // nullptr when unknown

}  // namespace epa::points
