#pragma once
// The one write gate. Every interface (Modbus, HTTP, and the ones to come) hands it a write of one
// point or a group, with who asks and what that client may do; the gate checks the group whole
// against the catalog's access, one set of limits (write_limits.hpp), the client's rights, the
// tuning lock, and the scan cycle's own rules in the state it last published
// (runtime/command_rules.hpp). It then either queues one command group for the loop and hands the
// audit trail its entries, or refuses with one kind and reason (gate_result.hpp) that each
// interface maps to its own error. Nothing is half-applied.
//
// The gate owns the running tuning: tuning writes edit its copy, which becomes the loop's whole
// at the next cycle; everyone else reads it (running_tuning(), the snapshot). It owns the next
// excitation experiment's settings the same way (the excite_* points, unlock-protected too).
//
// A command the gate accepted is refused by the loop only when the state changed in between (a
// fault latched, the recorder busy). take_refusals() collects those off the loop: each is logged
// and audited as refused, with the value the point kept, and counted in the snapshot.
//
// The positioning interface lives here too: the gate keeps the control word (so a single coil
// changes one bit of it), the selected record and the position-record table, and turns a start
// edge into one move command with the record's target, speed limit, window and law. Reads go
// through snapshot(): the loop's last snapshot with the writes it has not applied yet, so a read
// right after an acknowledged write returns the written value.
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "control/controller.hpp"
#include "core/audit.hpp"
#include "core/sensor_calibration.hpp"
#include "points/commission_control.hpp"
#include "points/health_control.hpp"
#include "points/gate_result.hpp"
#include "points/point_catalog.hpp"
#include "points/point_id.hpp"
#include "points/position_records.hpp"
#include "points/write_limits.hpp"
#include "runtime/loop_channels.hpp"

namespace epa::points {

struct PointWrite {
  PointId id = PointId::kCount;
  double value = 0;
};

// Who writes, as the interface knows it.
struct Requester {
  std::string source;            // for the audit trail and logs: "modbus 127.0.0.1:50312", "web 127.0.0.1"
  bool may_write = true;         // the interface's write policy for this client
  std::string no_write_reason;   // why not, when !may_write ("the Modbus server is read-only")
  bool tuning_unlocked = false;  // Modbus: the key was sent; HTTP: the token
  std::string tuning_locked_reason{};  // why tuning is refused when locked; "": unlock it first
};

class WriteGate {
 public:
  // `loop_rules` is the scan cycle's configuration (its command rules and sensor scale); `tuning`
  // the running tuning's configuration; `audit` may be null.
  WriteGate(WriteLimits limits, const runtime::RuntimeConfig& loop_rules, control::ControllerConfig tuning,
            runtime::LoopChannels& channels, core::AuditSink* audit, const PositionRecords& records = {});

  // The loop's last snapshot with the accepted writes it has not taken yet applied on top.
  runtime::Snapshot snapshot() const;
  PositionRecords records() const;
  int record_select() const;

  // Checks `writes` whole against the loop's current snapshot; queues and audits them, or refuses.
  GateResult submit(std::span<const PointWrite> writes, const Requester& who);

  // The same decision against the state `snap`, without queueing or auditing; on acceptance
  // `commands` holds what submit would queue (tests hold it against the loop's checks).
  GateResult decide(std::span<const PointWrite> writes, const Requester& who, const runtime::Snapshot& snap,
                    std::vector<runtime::Command>* commands = nullptr) const;

  // An event an interface decided on its own that belongs in the same audit trail (a refused
  // unlock attempt): recorded as it is, nothing queued.
  void record_event(const std::vector<core::AuditEntry>& entries) {
    if (audit_) audit_->record(entries);
  }

  // Another tuning set as a whole (the commissioning sequence deploying or rolling back): the loop
  // runs `tuning` with its controller from the next cycle on, and `entry` (e.g. running_tuning_set
  // old id -> new id) goes into the audit trail. Refused when the tuning does not validate or the
  // requester may not change tuning.
  GateResult replace_tuning(const control::ControllerConfig& tuning, const Requester& who, const core::AuditEntry& entry);

  // The commissioning service behind commission_command (none: the point is refused). Attach it
  // before the interfaces start; it must outlive them.
  void attach_commission(CommissionControl* commission) { commission_ = commission; }
  CommissionView commission_view() const { return commission_ ? commission_->view() : CommissionView{}; }
  // The model-health monitor behind health_command and the health points (none: state off, the
  // command refused). Attach it before the interfaces start; it must outlive them.
  void attach_health(HealthControl* health) { health_ = health; }
  HealthView health_view() const { return health_ ? health_->view() : HealthView{}; }
  HealthReport health_report(bool with_trend) const;

  // Logs and audits the commands the loop refused after the gate accepted them. Off the loop.
  void take_refusals(const std::function<void(const std::string&)>& log);

  control::ControllerConfig running_tuning() const;
  runtime::ExcitationSettings excitation_settings() const;  // what the next EXCITE starts with
  const WriteLimits& limits() const { return limits_; }
  ConfiguredLimits configured_limits() const;  // for the points an HMI reads them from
  core::ChangeCounters counters() const { return audit_ ? audit_->counters() : core::ChangeCounters{}; }

 private:
  struct Decision;
  GateResult commission(std::span<const PointWrite> writes, const Requester& who);
  GateResult health(std::span<const PointWrite> writes, const Requester& who);
  GateResult build(std::span<const PointWrite> writes, const Requester& who, const runtime::Snapshot& snap,
                   const control::ControllerConfig& tuning, const runtime::ExcitationSettings& excitation, Decision& out) const;
  // build's steps, in its order.
  GateResult check_values(std::span<const PointWrite> writes) const;
  static GateResult check_rights(std::span<const PointWrite> writes, const Requester& who);
  GateResult check_service_command(std::span<const PointWrite> writes) const;
  GateResult edit_records(std::span<const PointWrite> writes, Decision& out) const;
  GateResult add_commands(std::span<const PointWrite> writes, const runtime::Snapshot& snap, const control::ControllerConfig& tuning,
                          Decision& out) const;
  GateResult command_for(const PointWrite& w, std::span<const PointWrite> writes, const runtime::Snapshot& snap,
                         const control::ControllerConfig& tuning, Decision& out, runtime::Command& c) const;
  static runtime::Command control_command(std::uint16_t word, std::span<const PointWrite> writes, const runtime::Snapshot& snap, Decision& out);
  static void move_mode_first(Decision& out);
  GateResult check_loop_rules(const Decision& d, const runtime::Snapshot& snap, const runtime::ExcitationSettings& excitation) const;

  // An accepted, audited write whose command the loop may still refuse.
  struct InFlight {
    std::uint64_t sequence = 0;
    core::AuditEntry entry;
  };

  const WriteLimits limits_;
  const runtime::RuntimeConfig loop_rules_;
  const core::SensorCalibration sensor_;  // the loop's: tuning points in mm, the law's lengths in volts
  runtime::LoopChannels& channels_;
  core::AuditSink* audit_;
  CommissionControl* commission_ = nullptr;
  HealthControl* health_ = nullptr;

  mutable std::mutex mutex_;  // one writer at a time: Modbus and web threads
  control::ControllerConfig tuning_;
  runtime::ExcitationSettings excitation_;
  std::uint64_t next_sequence_ = 1;
  std::deque<InFlight> in_flight_;  // the last kInFlight accepted writes, for late refusals
  static constexpr std::size_t kInFlight = 1024;
  std::uint16_t control_word_ = 0;  // as accepted (the loop's follows within a cycle)
  int record_select_ = 0;
  PositionRecords records_;
  std::chrono::steady_clock::time_point last_record_request_{};  // record_s accepted; paced by record_min_interval_s
  // Accepted commands the loop may not have taken yet (snapshot() applies them); pruned by the
  // snapshot's last_sequence.
  mutable std::deque<runtime::Command> unapplied_;
  runtime::Snapshot with_unapplied(runtime::Snapshot s) const;  // mutex_ held
  void remember_unapplied(std::span<const runtime::Command> commands);  // queued: reads show them; mutex_ held
  static constexpr std::size_t kUnapplied = 256;
};

}  // namespace epa::points
