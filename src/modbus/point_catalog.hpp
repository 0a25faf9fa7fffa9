#pragma once
// The named points a register map can bind: everything an operator or integrator reads from the
// appliance (snapshot values, tuning, metrics, loop statistics, counters) and the few things they
// write (setpoint, mode, controller, manual valve, tuning, reset, heartbeat, record, unlock).
// The register map file decides where each point lives and how it is encoded; this catalog
// decides what the point means. `epa registers --points` lists it.
#include <cstdint>
#include <string_view>
#include <vector>

#include "runtime/snapshot.hpp"

namespace epa::modbus {

// What the Modbus server itself knows, for the points that describe it.
struct ServerStatus {
  std::uint32_t change_counter = 0;  // accepted changes since start, every interface
  std::uint32_t saved_counter = 0;   // how many of them are on disk
  bool saving = true;                // the store's writes succeed
  std::uint64_t requests = 0;
  int clients = 0;
  bool locked = true;                // tuning registers refuse writes
};

struct PointContext {
  const runtime::Snapshot& snapshot;
  const ServerStatus& server;
};

enum class WriteEffect : std::uint8_t {
  kNone,  // read-only
  kSetpoint, kMode, kController, kManualValve, kReset, kHeartbeat, kRecord, kUnlock,
  kDeadZoneMr, kDeadZoneMl, kDeadZoneBr, kDeadZoneBl, kLc,  // tuning: only while unlocked
};

struct PointDef {
  std::string_view name;
  std::string_view unit;
  std::string_view description;
  WriteEffect write = WriteEffect::kNone;
  double min = -1e300, max = 1e300;  // the values a write may carry, before any map range
  bool integer = false;              // writes must be whole numbers (enumerations, counters, keys)
  double (*read)(const PointContext&, int index) = nullptr;
  int index = 0;                     // for arrays: F0..F6 read F[index]
  bool writable() const { return write != WriteEffect::kNone; }
  bool tuning() const { return write >= WriteEffect::kDeadZoneMr; }
};

const std::vector<PointDef>& point_catalog();
const PointDef* find_point(std::string_view name);  // nullptr when unknown

inline constexpr int kVersionMajor = 0, kVersionMinor = 2, kVersionPatch = 0;

}  // namespace epa::modbus
