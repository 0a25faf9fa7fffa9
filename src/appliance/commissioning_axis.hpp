#pragma once
// The commissioning sequence's axis on the running appliance: commands go through the write gate
// (audited with the requester's source), state comes from the loop's snapshot, runs from the
// recorder, tuning sets from and into the store.
#include <string>

#include "appliance/recorded_runs.hpp"
#include "commission/axis.hpp"
#include "points/write_gate.hpp"
#include "runtime/loop_channels.hpp"
#include "runtime/runtime_config.hpp"
#include "store/store_writer.hpp"

namespace epa::appliance {

class CommissioningAxis final : public commission::Axis {
 public:
  CommissioningAxis(const runtime::RuntimeConfig& rules, runtime::LoopChannels& channels, points::WriteGate& gate,
                store::StoreWriter& store, std::string db_path, RecordedRuns& runs, points::Requester who)
      : rules_(rules), channels_(channels), gate_(gate), store_(store), db_path_(std::move(db_path)), runs_(runs), who_(std::move(who)) {}

  double position_mm() override { return channels_.snapshot.read().position_mm; }
  double setpoint_min_mm() const override { return rules_.setpoint_min_mm; }
  double setpoint_max_mm() const override { return rules_.setpoint_max_mm; }
  core::Result<core::Run> excite(const commission::ExcitationRequest& request, const std::atomic<bool>& abort) override;
  core::Result<commission::RunningTuning> running() override;
  core::Result<std::int64_t> save(const store::ModelRecord& model, const store::TuningSet& set) override;
  core::Status use_set(std::int64_t set_id, bool persist, const std::string& reason) override;
  core::Result<core::Run> move(double target_mm, double hold_s, const std::atomic<bool>& abort) override;
  void stop() override;

 private:
  core::Status write(std::initializer_list<points::PointWrite> writes);

  const runtime::RuntimeConfig& rules_;
  runtime::LoopChannels& channels_;
  points::WriteGate& gate_;
  store::StoreWriter& store_;
  std::string db_path_;
  RecordedRuns& runs_;
  points::Requester who_;
};

}  // namespace epa::appliance
