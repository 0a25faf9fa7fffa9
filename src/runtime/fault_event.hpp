#pragma once
// A fault as the scan cycle saw it in the cycle that latched it, handed to the supervisor through
// LoopChannels::fault_events. The snapshot only shows the fault latched now, which a reset in the
// next cycle clears; the event keeps the cause. Fixed-size and trivially copyable: the loop
// copies it into the ring without allocating.
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "hal/daq.hpp"
#include "runtime/mode.hpp"

namespace epa::runtime {

struct FaultEvent {
  std::uint64_t cycle = 0;   // the cycle that latched it
  double loop_time_s = 0;    // cycle * Ts, the snapshot's time_s clock
  FaultCode code = FaultCode::kNone;
  Mode mode = Mode::kStop;   // the mode it was in before the fault
  double position_mm = 0, setpoint_mm = 0;
  double valve_v = 0;        // the command applied when it happened (written in the cycle before)
  double sensor_v = 0;       // the reading that cycle (NaN: none yet)
  // I/O in a row up to it: failed reads and writes, and how the last of each went (io-errors'
  // cause: a module that does not answer times out; a link that is down or a module that answers
  // with an error reports one).
  int failed_reads = 0, failed_writes = 0;
  hal::IoStatus last_read = hal::IoStatus::kOk, last_write = hal::IoStatus::kOk;
};
static_assert(std::is_trivially_copyable_v<FaultEvent>);

// The supervisor drains the ring every 50 ms, and each fault needs a reset before the next: at
// Ts = 5 ms that is at most 10 a drain. A full ring drops the event and counts it
// (Snapshot::fault_events_dropped).
inline constexpr std::size_t kFaultEventCapacity = 32;

}  // namespace epa::runtime
