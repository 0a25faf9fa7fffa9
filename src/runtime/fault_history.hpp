#pragma once
// The fault history the interfaces read: the newest faults with their cause, newest first, at
// most kFaultHistoryEntries, and how many faults there have been. The supervisor appends each
// event the loop hands it (and the store keeps them); at start it is loaded from the store, so
// `total` counts every fault since the store was created (as far as the store saved them: a
// fault still queued for the disk at a crash is not counted after the restart). Thread-safe: the
// supervisor writes, the Modbus and web threads read. The scan cycle never touches it.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "runtime/fault_event.hpp"
#include "runtime/mode.hpp"

namespace epa::runtime {

inline constexpr std::size_t kFaultHistoryEntries = 64;  // in memory and in the store

struct FaultRecord {
  std::int64_t time_ms = 0;  // wall clock when it latched, unix ms
  FaultCode code = FaultCode::kNone;  // kNone: an empty slot
  Mode mode = Mode::kStop;   // the mode it was in before the fault
  double position_mm = std::numeric_limits<double>::quiet_NaN();  // NaN: not known
  double setpoint_mm = std::numeric_limits<double>::quiet_NaN();
  double valve_v = std::numeric_limits<double>::quiet_NaN();
  double sensor_v = std::numeric_limits<double>::quiet_NaN();
  std::string name, text;    // the fault's name and sentence as written when it happened
};

// The record of `event`, stamped `time_ms`, with this epa's name and sentence for its code.
FaultRecord fault_record(const FaultEvent& event, std::int64_t time_ms);

// When the loop latched `event`, on the wall clock: `now_ms` less how far the loop's clock
// (`loop_now_s`, a snapshot's time_s read after the event was taken) has run since.
std::int64_t fault_time_ms(const FaultEvent& event, double loop_now_s, std::int64_t now_ms);

class FaultHistory {
 public:
  // Run before every read, outside the lock: adds what the loop has latched and nobody has added
  // yet (serve drains the loop's fault-event ring with it). So a client that has read a fault in a
  // snapshot finds it here at once, however quickly it was reset, instead of one supervisor tick
  // (50 ms) later. Set before the reading threads start; it must be safe to call from several.
  void set_intake(std::function<void()> intake) { intake_ = std::move(intake); }

  // What the store kept (newest first; only the newest kFaultHistoryEntries are used) and how many
  // faults it has recorded in all. Replaces what was there.
  void load(std::span<const FaultRecord> newest_first, std::uint64_t total);
  // The newest fault.
  void add(FaultRecord record);

  // Newest first; `total` (when given) gets total() under the same lock, so the two agree.
  std::vector<FaultRecord> newest(std::size_t limit = kFaultHistoryEntries, std::uint64_t* total = nullptr) const;
  std::uint64_t total() const;
  // The newest out.size() into `out`, newest first, empty slots (code kNone, NaN) after them;
  // returns total(). One lock for both, so the count and the entries agree.
  std::uint64_t copy_newest(std::span<FaultRecord> out) const;

 private:
  void take_in() const {
    if (intake_) intake_();
  }

  std::function<void()> intake_;
  mutable std::mutex mutex_;
  std::deque<FaultRecord> entries_;  // newest first
  std::uint64_t total_ = 0;
};

}  // namespace epa::runtime
