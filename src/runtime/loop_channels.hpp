#pragma once
// What the scan cycle shares with the other threads: the command queue in, the snapshot out, the
// sample ring and record requests for the recorder, refusals for the write gate, and faults for
// the supervisor. Every interface (Modbus, HTTP, the recorder) meets the loop through these alone,
// so it includes this header, not the loop's.
#include <cstddef>
#include <cstdint>

#include "control/controller_kind.hpp"
#include "runtime/command.hpp"
#include "runtime/command_queue.hpp"
#include "runtime/command_rules.hpp"
#include "runtime/excitation_run.hpp"
#include "runtime/excitation_settings.hpp"
#include "runtime/fault_event.hpp"
#include "runtime/fault_history.hpp"
#include "runtime/move_tracker.hpp"
#include "runtime/sample_ring.hpp"
#include "runtime/seqlock.hpp"
#include "runtime/snapshot.hpp"
#include "runtime/spsc_ring.hpp"

namespace epa::runtime {

// Asks the recorder thread to write samples [first, end) as a run file.
struct RecordRequest {
  enum class Reason : std::uint8_t { kMove, kRequest, kExcitation } reason = Reason::kRequest;
  std::uint64_t first = 0, end = 0;
  MoveResult move;  // for kMove
  double ess_window_s = 0;  // for kMove: the window of its e_ss (core::move_metrics)
  control::ControllerKind controller = control::ControllerKind::kPpFfidz;
  bool open_loop = false;  // no controller drove any of the samples (MANUAL, EXCITE, STOP): controller=open-loop
  ExcitationSettings excitation;                          // for kExcitation
  ExcitationEnd excitation_end = ExcitationEnd::kComplete;  // for kExcitation
  std::uint32_t pulses = 0, pulses_cut = 0;                 // for kExcitation: pulses given, and cut at a guard line
};

inline constexpr std::size_t kCommandQueueCapacity = 64;

// The two channels other threads meet the loop through, plus the recorder's and the supervisor's.
struct LoopChannels {
  explicit LoopChannels(std::size_t record_capacity) : samples(record_capacity) {}
  CommandQueue<Command, kCommandQueueCapacity> commands;
  SeqlockCell<Snapshot> snapshot;
  SampleRing samples;
  SpscRing<RecordRequest, 16> record_requests;
  SpscRing<CommandOutcome, 64> refusals;  // commands the loop refused, for the gate to log and audit
  SpscRing<FaultEvent, kFaultEventCapacity> fault_events;  // faults the loop latched, for the supervisor
  // What the supervisor made of fault_events (the loop never touches it): here because every
  // interface meets the loop through these channels, so each reads the one history.
  FaultHistory fault_history;
};

}  // namespace epa::runtime
