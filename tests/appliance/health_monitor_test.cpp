// The appliance's model-health monitor: which recorded runs it judges, the verdict it publishes
// for the interfaces, what it audits, and how it follows the running tuning set. The axis is the
// stick-slip model itself (tests/support/stick_slip_axis.hpp), so what it names is known.
#include "appliance/health_monitor.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <vector>

#include "../support/physics_identified_model.hpp"
#include "../support/stick_slip_axis.hpp"
#include "core/model_file.hpp"
#include "points/point_catalog.hpp"

namespace epa::appliance {
namespace {

using points::HealthEffectCode;
using points::HealthStateCode;

core::ModelFile identified_model() {
  auto f = core::parse_model_toml(testing::kPhysicsIdentifiedModelToml, "identified");
  EXPECT_TRUE(f.has_value());
  return *f;
}

class RecordingAudit : public core::AuditSink {
 public:
  void record(const std::vector<core::AuditEntry>& change) override {
    std::lock_guard lock(mutex_);
    entries_.insert(entries_.end(), change.begin(), change.end());
  }
  std::vector<core::AuditEntry> entries() const {
    std::lock_guard lock(mutex_);
    return entries_;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<core::AuditEntry> entries_;
};

config::HealthSettings switched_on() {
  config::HealthSettings s;
  s.enabled = true;
  return s;
}

// A monitor whose running set is `set_id` (changed by the test) with the identified model, or
// with no stick-slip table when `with_stick_slip` is false.
struct Rig {
  explicit Rig(bool with_stick_slip = true, config::HealthSettings settings = switched_on())
      : model(identified_model()),
        monitor(
            settings, [this] { return set_id.load(); },
            [this, with_stick_slip](std::int64_t id) -> core::Result<MonitoredModel> {
              ++model_reads;
              return MonitoredModel{"set " + std::to_string(id), with_stick_slip ? model.stick_slip : std::nullopt, model.model.Ts};
            },
            &audit, [](bool, const std::string&) {},
            [this](const std::string& text) {
              std::lock_guard lock(history_mutex);
              history.push_back(text);
            }) {}

  // `n` moves of the axis, each judged before the next is added.
  void moves(testing::StickSlipAxis& axis, int n) {
    for (int i = 0; i < n; ++i) {
      monitor.add_run(axis.next_move(), false);
      ASSERT_TRUE(monitor.wait_idle(60'000));
    }
  }
  // The audit entries of health_state: (old, new) codes.
  std::vector<std::pair<int, int>> state_changes() const {
    std::vector<std::pair<int, int>> out;
    for (const auto& e : audit.entries())
      if (e.point == points::name(points::PointId::kHealthState)) out.emplace_back(int(e.old_value), int(e.new_value));
    return out;
  }

  std::vector<std::string> history_notes() const {
    std::lock_guard lock(history_mutex);
    return history;
  }

  core::ModelFile model;
  mutable std::mutex history_mutex;
  std::vector<std::string> history;  // what the monitor gave the fault history
  std::atomic<std::int64_t> set_id{1};
  std::atomic<int> model_reads{0};
  RecordingAudit audit;
  HealthMonitor monitor;
};

TEST(HealthMonitor, ASetWithoutAStickSlipModelIsNotMonitoredAndSaysWhy) {
  Rig rig(/*with_stick_slip=*/false);
  testing::StickSlipAxis axis(rig.model, *rig.model.stick_slip, 1);
  rig.moves(axis, 3);
  const auto r = rig.monitor.report(true);
  EXPECT_EQ(r.view.state, HealthStateCode::kOff);
  EXPECT_EQ(r.view.moves_seen, 0u);
  EXPECT_NE(r.reason.find("no stick-slip model"), std::string::npos) << r.reason;
  EXPECT_NE(r.reason.find("set 1"), std::string::npos) << r.reason;
}

TEST(HealthMonitor, SwitchedOffItJudgesNothing) {
  config::HealthSettings off = switched_on();
  off.enabled = false;
  Rig rig(true, off);
  testing::StickSlipAxis axis(rig.model, *rig.model.stick_slip, 1);
  rig.monitor.add_run(axis.next_move(), false);
  EXPECT_TRUE(rig.monitor.wait_idle(1000));
  EXPECT_EQ(rig.monitor.view().state, HealthStateCode::kOff);
  EXPECT_NE(rig.monitor.report(true).reason.find("enabled = false"), std::string::npos);
  EXPECT_EQ(rig.model_reads.load(), 0);
}

TEST(HealthMonitor, OnlyWholeClosedLoopMovesFromRestAreJudged) {
  Rig rig;
  testing::StickSlipAxis axis(rig.model, *rig.model.stick_slip, 1);
  ASSERT_TRUE(rig.monitor.wait_idle(5000));
  EXPECT_EQ(rig.monitor.view().state, HealthStateCode::kLearning);  // from the start, before any move

  rig.moves(axis, 1);  // the first move seen: what the piston did before it is not known
  EXPECT_EQ(rig.monitor.view().moves_seen, 0u);
  rig.moves(axis, 1);
  EXPECT_EQ(rig.monitor.view().moves_seen, 1u);

  auto cut = axis.next_move();
  cut.set_meta("move_end", "cut_short");
  auto after_cut = axis.next_move();  // starts with the piston sliding
  auto open_loop = axis.next_move();
  open_loop.set_meta("controller", "open-loop");
  auto lost = axis.next_move();
  lost.set_meta("samples_lost", "40");
  auto excitation = lost;  // a run without a move number (an excitation, a record request)
  excitation.metadata.erase(std::remove_if(excitation.metadata.begin(), excitation.metadata.end(),
                                           [](const auto& kv) { return kv.first == "move"; }),
                            excitation.metadata.end());
  for (auto* run : {&cut, &after_cut, &open_loop, &lost, &excitation}) rig.monitor.add_run(*run, false);
  ASSERT_TRUE(rig.monitor.wait_idle(5000));
  EXPECT_EQ(rig.monitor.view().moves_seen, 1u);

  rig.moves(axis, 1);  // follows `lost`, a whole move of its own
  EXPECT_EQ(rig.monitor.view().moves_seen, 2u);
}

TEST(HealthMonitor, FrictionDoubledIsPublishedAuditedAndWarns) {
  Rig rig;
  const auto p = *rig.model.stick_slip;
  testing::StickSlipAxis axis(rig.model, p, 2);
  rig.moves(axis, 28);
  EXPECT_EQ(rig.monitor.view().state, HealthStateCode::kOk);
  auto changed = p;
  changed.static_mm *= 2.0, changed.coulomb_mm *= 2.0;
  axis.change(changed);
  int named_after = -1;
  for (int m = 1; m <= 24 && named_after < 0; ++m) {
    rig.moves(axis, 1);
    if (rig.monitor.view().state == HealthStateCode::kDrifting) named_after = m;
  }
  ASSERT_GT(named_after, 0) << "friction x2 never named";
  const auto r = rig.monitor.report(true);
  EXPECT_EQ(r.view.effect, HealthEffectCode::kStaticFriction);
  EXPECT_NEAR(r.view.ratio, 2.0, 0.6);
  EXPECT_NEAR(r.view.value / r.view.commissioned, r.view.ratio, 1e-9);
  EXPECT_EQ(r.unit, "mm");
  EXPECT_NE(r.size.find("friction"), std::string::npos) << r.size;
  EXPECT_GE(r.view.moves_since_onset, 1u);
  EXPECT_LE(r.view.moves_since_onset, static_cast<std::uint32_t>(named_after) + 8);  // at most a window before it was named
  EXPECT_FALSE(r.trend.empty());
  EXPECT_EQ(r.trend.back().move, r.view.moves_seen);

  // The status word warns (bits 6 and 14), from the interfaces' view of the verdict.
  points::InterfaceStatus status;
  status.health = rig.monitor.view();
  const std::uint16_t word = points::status_word(runtime::Snapshot{}, status);
  EXPECT_TRUE(word & (1u << runtime::kStatusHealthWarning));
  EXPECT_TRUE(word & (1u << runtime::kStatusWarning));

  const auto changes = rig.state_changes();
  ASSERT_GE(changes.size(), 3u);
  EXPECT_EQ(changes[0], std::make_pair(int(HealthStateCode::kOff), int(HealthStateCode::kLearning)));
  EXPECT_EQ(changes[1], std::make_pair(int(HealthStateCode::kLearning), int(HealthStateCode::kOk)));
  EXPECT_EQ(changes.back(), std::make_pair(int(HealthStateCode::kOk), int(HealthStateCode::kDrifting)));
  EXPECT_NE(rig.audit.entries().back().source.find("friction"), std::string::npos) << rig.audit.entries().back().source;

  // The fault history gets the warning, not the learning before it; and its end.
  auto notes = rig.history_notes();
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("ok -> drifting"), std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("friction"), std::string::npos) << notes[0];
  rig.monitor.retake_baseline("web 127.0.0.1:4000");
  ASSERT_TRUE(rig.monitor.wait_idle(5000));
  notes = rig.history_notes();
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_NE(notes[1].find("drifting -> learning"), std::string::npos) << notes[1];
}

TEST(HealthMonitor, ARetakenBaselineAndAnotherRunningSetStartLearningAgain) {
  Rig rig;
  testing::StickSlipAxis axis(rig.model, *rig.model.stick_slip, 3);
  rig.moves(axis, 28);
  ASSERT_EQ(rig.monitor.view().state, HealthStateCode::kOk);

  rig.monitor.retake_baseline("modbus 127.0.0.1:5000");
  ASSERT_TRUE(rig.monitor.wait_idle(5000));
  EXPECT_EQ(rig.monitor.view().state, HealthStateCode::kLearning);
  EXPECT_EQ(rig.monitor.view().moves_seen, 0u);
  EXPECT_NE(rig.audit.entries().back().source.find("modbus 127.0.0.1:5000"), std::string::npos);

  // A move that starts before the piston came to rest is not judged: the baseline may need more.
  for (int m = 0; m < 40 && rig.monitor.view().state == HealthStateCode::kLearning; ++m) rig.moves(axis, 1);
  ASSERT_EQ(rig.monitor.view().state, HealthStateCode::kOk);
  EXPECT_EQ(rig.monitor.view().moves_seen, 24u);
  const int reads = rig.model_reads.load();
  rig.set_id = 2;  // commissioning deployed another set
  rig.moves(axis, 1);
  EXPECT_EQ(rig.model_reads.load(), reads + 1);
  EXPECT_EQ(rig.monitor.view().state, HealthStateCode::kLearning);
  EXPECT_EQ(rig.monitor.view().moves_seen, 1u);
}

}  // namespace
}  // namespace epa::appliance
