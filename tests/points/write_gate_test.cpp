// The one write gate, held against what it must guarantee: every writable point outside its one
// set of limits is refused with the limit named and nothing queued or audited; every write it
// accepts is applied by a real scan cycle in the same state; and a refusal that arises after it
// looked is counted, logged and audited as refused.
#include "points/write_gate.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include <utility>

#include <cmath>
#include <limits>

#include "../runtime/fake_daq.hpp"
#include "control/paper_controller.hpp"
#include "modbus/refusal_exception.hpp"
#include "points/point_catalog.hpp"
#include "runtime/scan_cycle.hpp"
#include "runtime/tuning.hpp"
#include "web/refusal_status.hpp"

namespace epa::points {
namespace {

using runtime::Mode;
using web::http_status;

// The codes each interface answers a refusal with (modbus/, web/): held here against the gate's kinds.
std::uint8_t modbus_exception(Refusal r) { return modbus::exception_code(r); }

struct RecordingSink final : core::AuditSink {
  std::vector<core::AuditEntry> entries;
  void record(const std::vector<core::AuditEntry>& change) override { entries.insert(entries.end(), change.begin(), change.end()); }
};

control::ControllerConfig paper() { return control::paper_controller_config(control::ControllerKind::kPpFfidz); }

// The integrator's case of the issue: [limits] setpoint_max_mm = 300, the catalog allows 500.
runtime::RuntimeConfig narrowed_config() {
  runtime::RuntimeConfig c;
  c.setpoint_max_mm = 300.0;
  return c;
}

WriteLimits limits_of(const runtime::RuntimeConfig& c) {
  auto l = WriteLimits::from_config(c, "epa.toml");
  EXPECT_TRUE(l.has_value()) << l.error().message;
  return *l;
}

const Requester kOperator{"test", true, "", /*tuning_unlocked=*/true};

std::vector<const PointDef*> gated_points() {
  std::vector<const PointDef*> out;
  for (const auto& p : point_catalog())
    if (p.gated()) out.push_back(&p);
  return out;
}

// A value just beyond a bound: far enough that no rounding brings it back.
double beyond(double bound, double direction) { return bound + direction * std::max(1.0, std::abs(bound) * 1e-3); }

TEST(WriteGate, EveryWritablePointOutsideItsLimitsIsRefusedNamingTheLimitAndNothingIsQueuedOrAudited) {
  const auto config = narrowed_config();
  runtime::LoopChannels channels(16);
  runtime::Snapshot snap;
  snap.mode = Mode::kManual;  // the mode rules would allow the manual valve: the range must refuse it
  channels.snapshot.publish(snap);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  int checked = 0;
  for (const PointDef* p : gated_points()) {
    const PointRange& r = gate.limits().range(p->id);
    for (const auto& [value, bound] : {std::pair{beyond(r.max.value, +1), &r.max}, std::pair{beyond(r.min.value, -1), &r.min},
                                       std::pair{std::numeric_limits<double>::quiet_NaN(), &r.max}}) {
      const PointWrite w{p->id, value};
      const GateResult result = gate.submit({&w, 1}, kOperator);
      EXPECT_EQ(result.refusal, Refusal::kInvalidValue) << p->name << " = " << value;
      EXPECT_NE(result.reason.find(std::string(p->name)), std::string::npos) << result.reason;
      EXPECT_NE(result.reason.find(bound->source), std::string::npos) << result.reason;
      EXPECT_EQ(modbus_exception(result.refusal), 0x03);
      EXPECT_EQ(http_status(result.refusal), 400);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 3 * static_cast<int>(gated_points().size()));
  EXPECT_GE(gated_points().size(), 12u);  // setpoint, mode, controller, manual valve, reset, heartbeat, record, 5 tuning
  runtime::Command c;
  EXPECT_FALSE(channels.commands.try_pop(c));
  EXPECT_TRUE(sink.entries.empty());
}

TEST(WriteGate, TheConfigurationNarrowsTheCatalogAndTheRefusalSaysWhichKey) {
  const auto config = narrowed_config();
  runtime::LoopChannels channels(16);
  WriteGate gate(limits_of(config), config, paper(), channels, nullptr);
  const PointWrite w{PointId::kSetpoint, 400.0};
  const auto r = gate.submit({&w, 1}, kOperator);
  EXPECT_EQ(r.refusal, Refusal::kInvalidValue);
  EXPECT_EQ(r.reason, "setpoint_mm 400 is outside [0, 300] mm (maximum from epa.toml [limits] setpoint_max_mm)");
}

TEST(WriteGate, ConfigurationsAndMapsThatContradictTheCatalogAreRefused) {
  runtime::RuntimeConfig c;
  c.setpoint_max_mm = 800.0;  // beyond the stroke the catalog allows
  const auto l = WriteLimits::from_config(c, "epa.toml");
  ASSERT_FALSE(l.has_value());
  EXPECT_NE(l.error().message.find("setpoint_max_mm"), std::string::npos) << l.error().message;
  auto limits = limits_of(narrowed_config());
  const auto s = limits.narrow(PointId::kSetpoint, 350.0, 500.0, "map.csv:2");  // nothing left of [0, 300]
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("map.csv:2"), std::string::npos) << s.error().message;
  ASSERT_TRUE(limits.narrow(PointId::kSetpoint, 10.0, 500.0, "map.csv:2"));
  EXPECT_EQ(limits.range(PointId::kSetpoint).min.value, 10.0);
  EXPECT_EQ(limits.range(PointId::kSetpoint).min.source, "map.csv:2");
  EXPECT_EQ(limits.range(PointId::kSetpoint).max.value, 300.0);
}

TEST(WriteGate, RightsLockAndAccessAreCheckedAfterTheValues) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  const PointWrite lc{PointId::kLc, 3.0};
  EXPECT_EQ(gate.submit({&lc, 1}, Requester{"test", true, "", false}).refusal, Refusal::kForbidden);
  const auto no_rights = gate.submit({&lc, 1}, Requester{"test", false, "the Modbus server is read-only", true});
  EXPECT_EQ(no_rights.refusal, Refusal::kForbidden);
  EXPECT_EQ(no_rights.reason, "the Modbus server is read-only");
  const PointWrite position{PointId::kPosition, 1.0}, key{PointId::kUnlock, 1.0};
  EXPECT_EQ(gate.submit({&position, 1}, kOperator).refusal, Refusal::kNotWritable);
  EXPECT_EQ(gate.submit({&key, 1}, kOperator).refusal, Refusal::kNotWritable);  // the key is its interface's own
  EXPECT_TRUE(sink.entries.empty());
  EXPECT_TRUE(gate.submit({&lc, 1}, kOperator).accepted());
  EXPECT_DOUBLE_EQ(gate.running_tuning().lc_v, 3.0 / config.mm_per_volt);  // the gate owns the running tuning
  ASSERT_EQ(sink.entries.size(), 1u);
  EXPECT_EQ(sink.entries[0].point, "lc_mm");
}

// A commissioning service that records the calls the gate made.
struct FakeCommission final : CommissionControl {
  CommissionStartResult start(const std::string& spec, const std::string& source) override {
    if (running) return {CommissionStart::kBusy, "a commissioning run is under way"};
    running = true;
    starts.push_back(source + (spec.empty() ? "" : " " + spec));
    return {};
  }
  bool abort(const std::string&) override { return std::exchange(running, false); }
  CommissionView view() const override { return {true, running, running ? 1 : 0, 0, 0.0}; }
  bool running = false;
  std::vector<std::string> starts;
};

TEST(WriteGate, CommissionCommandIsUnlockProtectedWrittenAloneAndGoesToTheServiceNotTheLoop) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  const PointWrite start{PointId::kCommissionCommand, 1.0}, abort{PointId::kCommissionCommand, 2.0};
  EXPECT_EQ(gate.submit({&start, 1}, kOperator).refusal, Refusal::kNotWritable);  // no service attached
  FakeCommission service;
  gate.attach_commission(&service);
  EXPECT_EQ(gate.submit({&start, 1}, Requester{"modbus 127.0.0.1:5000", true, "", false}).refusal, Refusal::kForbidden);
  const PointWrite three{PointId::kCommissionCommand, 3.0};
  EXPECT_EQ(gate.submit({&three, 1}, kOperator).refusal, Refusal::kInvalidValue);
  const std::vector<PointWrite> group = {{PointId::kSetpoint, 100.0}, {PointId::kCommissionCommand, 1.0}};
  EXPECT_EQ(gate.submit(group, kOperator).refusal, Refusal::kInvalidValue);
  EXPECT_TRUE(service.starts.empty());
  EXPECT_TRUE(sink.entries.empty());

  ASSERT_TRUE(gate.submit({&start, 1}, kOperator).accepted());
  EXPECT_EQ(service.starts, std::vector<std::string>{"test"});
  runtime::Command c;
  EXPECT_FALSE(channels.commands.try_pop(c));  // nothing for the loop
  EXPECT_TRUE(gate.commission_view().running);
  EXPECT_EQ(gate.submit({&start, 1}, kOperator).refusal, Refusal::kConflict);  // one run at a time
  ASSERT_TRUE(gate.submit({&abort, 1}, kOperator).accepted());
  EXPECT_EQ(gate.submit({&abort, 1}, kOperator).refusal, Refusal::kConflict);  // nothing to abort
  // The service audits a start and an abort, each under its own source, for every interface
  // (appliance/commissioning_service.cpp); the gate adds no second entry.
  EXPECT_TRUE(sink.entries.empty());
}

// A model-health monitor that records the retakes the gate asked for.
struct FakeHealth final : HealthControl {
  HealthView view() const override { return {HealthStateCode::kDrifting, HealthEffectCode::kStaticFriction, 14.0, 7.0, 2.0, 40, 6}; }
  HealthReport report(bool) const override { return {view(), "friction up 100 %", "mm", "", 0.5, 0.2, 0, {}}; }
  void retake_baseline(const std::string& source) override { retakes.push_back(source); }
  std::vector<std::string> retakes;
};

TEST(WriteGate, HealthCommandIsUnlockProtectedWrittenAloneAndRetakesTheMonitorsBaseline) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  const PointWrite retake{PointId::kHealthCommand, 1.0};
  EXPECT_EQ(gate.health_view().state, HealthStateCode::kOff);  // no monitor attached
  const auto none = gate.submit({&retake, 1}, kOperator);
  EXPECT_EQ(none.refusal, Refusal::kNotWritable);
  EXPECT_NE(none.reason.find("health_command"), std::string::npos) << none.reason;
  FakeHealth health;
  gate.attach_health(&health);
  EXPECT_EQ(gate.submit({&retake, 1}, Requester{"modbus 127.0.0.1:5000", true, "", false}).refusal, Refusal::kForbidden);
  const PointWrite two{PointId::kHealthCommand, 2.0};
  EXPECT_EQ(gate.submit({&two, 1}, kOperator).refusal, Refusal::kInvalidValue);
  const std::vector<PointWrite> group = {{PointId::kSetpoint, 100.0}, {PointId::kHealthCommand, 1.0}};
  EXPECT_EQ(gate.submit(group, kOperator).refusal, Refusal::kInvalidValue);
  EXPECT_TRUE(health.retakes.empty());

  ASSERT_TRUE(gate.submit({&retake, 1}, kOperator).accepted());
  EXPECT_EQ(health.retakes, std::vector<std::string>{"test"});
  runtime::Command c;
  EXPECT_FALSE(channels.commands.try_pop(c));  // nothing for the loop
  EXPECT_TRUE(sink.entries.empty());           // the monitor audits the retake under its source
  EXPECT_EQ(gate.health_view().effect, HealthEffectCode::kStaticFriction);
  EXPECT_EQ(gate.health_report(false).size, "friction up 100 %");
}

TEST(WriteGate, AGroupIsTakenWholeOrNotAtAll) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  const PointWrite bad[] = {{PointId::kSetpoint, 100.0}, {PointId::kBl, 2.0}};  // b_l > b_r: the tuning does not validate
  const auto r = gate.submit(bad, kOperator);
  EXPECT_EQ(r.refusal, Refusal::kInvalidValue);
  EXPECT_NE(r.reason.find("tuning"), std::string::npos) << r.reason;
  runtime::Command c;
  EXPECT_FALSE(channels.commands.try_pop(c));
  EXPECT_TRUE(sink.entries.empty());
  const PointWrite good[] = {{PointId::kMode, 1.0}, {PointId::kSetpoint, 100.0}, {PointId::kBr, 1.3}, {PointId::kMr, 2.0}};
  ASSERT_TRUE(gate.submit(good, kOperator).accepted());
  std::vector<runtime::CommandKind> kinds;
  while (channels.commands.try_pop(c)) kinds.push_back(c.kind);
  EXPECT_EQ(kinds, (std::vector{runtime::CommandKind::kMode, runtime::CommandKind::kSetpoint, runtime::CommandKind::kTuning}));
  EXPECT_EQ(sink.entries.size(), 4u);
}

// A held jog is kept alive by writing the control word again as it is, several times a second:
// those writes are no change, so they stay out of the audit trail (and the store); the press and
// the release are in it.
TEST(WriteGate, AControlWordWrittenAgainAsItIsIsAKeepAliveNotAnAuditedChange) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  const PointWrite manual[] = {{PointId::kMode, 2.0}};
  ASSERT_TRUE(gate.submit(manual, kOperator).accepted());
  const PointWrite jog[] = {{PointId::kControlWord, 4.0}};
  const PointWrite jog_bit[] = {{points::indexed_id(PointId::kControlBit0, 2), 1.0}};
  const PointWrite release[] = {{PointId::kControlWord, 0.0}};
  for (const auto* group : {jog, jog, jog, jog_bit, release}) ASSERT_TRUE(gate.submit({group, 1}, kOperator).accepted());
  std::vector<std::string> audited;
  for (const auto& e : sink.entries) audited.push_back(e.point + " " + std::to_string(int(e.old_value)) + "->" + std::to_string(int(e.new_value)));
  EXPECT_EQ(audited, (std::vector<std::string>{"mode 0->2", "control_word 0->4", "control_word 4->0"}));
  runtime::Command c;
  int queued = 0;
  while (channels.commands.try_pop(c)) queued += c.kind == runtime::CommandKind::kControl;
  EXPECT_EQ(queued, 5);  // every write still reaches the loop: it is the keep-alive
}

// A record's start carries its side of approach to the loop: from above as -1, the near side as 0.
TEST(WriteGate, ARecordsStartCarriesItsSideOfApproach) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  WriteGate gate(limits_of(config), config, paper(), channels, nullptr);
  const PointWrite run[] = {{PointId::kMode, 1.0}};
  ASSERT_TRUE(gate.submit(run, kOperator).accepted());
  const PointWrite record[] = {{points::indexed_id(PointId::kRecordTarget0, 0), 200.0},
                               {points::indexed_id(PointId::kRecordApproach0, 0), 2.0},
                               {points::indexed_id(PointId::kRecordTarget0, 1), 100.0},
                               {PointId::kRecordSelect, 1.0}};
  ASSERT_TRUE(gate.submit(record, kOperator).accepted());
  const PointWrite start[] = {{PointId::kControlWord, 1.0}};
  const PointWrite release[] = {{PointId::kControlWord, 0.0}};
  const PointWrite select2[] = {{PointId::kRecordSelect, 2.0}};
  const PointWrite bad_side[] = {{points::indexed_id(PointId::kRecordApproach0, 0), 3.0}};
  EXPECT_FALSE(gate.submit(bad_side, kOperator).accepted());
  for (const auto* group : {start, release, select2, start}) ASSERT_TRUE(gate.submit({group, 1}, kOperator).accepted());
  std::vector<std::pair<double, double>> starts;  // target, side
  runtime::Command c;
  while (channels.commands.try_pop(c))
    if (c.kind == runtime::CommandKind::kControl && (c.control_word & runtime::kControlStart)) starts.emplace_back(c.value, c.approach_direction);
  EXPECT_EQ(starts, (std::vector<std::pair<double, double>>{{200.0, -1.0}, {100.0, 0.0}}));
}

// A read right after a mode change shows the motion bits as the new mode will have them, not the
// old mode's: RUN's in_position and a halt's halted must not read beside manual_mode.
TEST(WriteGate, AModeChangeNotYetAppliedReadsWithTheNewModesMotionBits) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  WriteGate gate(limits_of(config), config, paper(), channels, nullptr);
  runtime::Snapshot s;
  s.mode = Mode::kRun;
  s.axis.in_position = s.axis.halted = s.axis.target_reached = true;
  s.manual_valve_v = 1.5;
  channels.snapshot.publish(s);
  const PointWrite manual[] = {{PointId::kMode, 2.0}};
  ASSERT_TRUE(gate.submit(manual, kOperator).accepted());
  const runtime::Snapshot seen = gate.snapshot();
  EXPECT_EQ(seen.mode, Mode::kManual);
  EXPECT_FALSE(seen.axis.in_position);
  EXPECT_FALSE(seen.axis.halted);
  EXPECT_FALSE(seen.axis.target_reached);
  EXPECT_EQ(seen.manual_valve_v, config.safe_valve_v);
}

TEST(WriteGate, PpTrajIsRefusedOnAModelItCannotUseAndTakenOnOneItCan) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  auto not_integrating = paper();
  not_integrating.A = core::Polynomial({1.0, -0.5});
  WriteGate refusing(limits_of(config), config, not_integrating, channels, &sink);
  const PointWrite traj[] = {{PointId::kController, 3.0}};
  const auto r = refusing.submit(traj, kOperator);
  EXPECT_EQ(r.refusal, Refusal::kInvalidValue);
  EXPECT_NE(r.reason.find("integrates"), std::string::npos) << r.reason;
  runtime::Command c;
  EXPECT_FALSE(channels.commands.try_pop(c));
  EXPECT_TRUE(sink.entries.empty());

  WriteGate taking(limits_of(config), config, paper(), channels, &sink);
  ASSERT_TRUE(taking.submit(traj, kOperator).accepted());
  ASSERT_TRUE(channels.commands.try_pop(c));
  EXPECT_EQ(c.controller, control::ControllerKind::kPpTraj);
  // Its settings are tuning points: checked whole (a speed fraction of 0 would not validate).
  const PointWrite band[] = {{PointId::kTrajHoldBand, 0.2}, {PointId::kTrajBandwidth, 6.0}};
  ASSERT_TRUE(taking.submit(band, kOperator).accepted());
  ASSERT_TRUE(channels.commands.try_pop(c));
  ASSERT_EQ(c.kind, runtime::CommandKind::kTuning);
  EXPECT_DOUBLE_EQ(c.tuning.traj.trajectory_config().hold_band_v * 50.0, 0.2);
  EXPECT_DOUBLE_EQ(c.tuning.traj.trajectory_config().feedback_bandwidth_rad_s, 6.0);
}

TEST(WriteGate, ExcitationSettingsAreUnlockProtectedCheckedWholeAndQueuedBeforeTheModeChange) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  runtime::Snapshot stopped;
  stopped.position_mm = 250.0;
  channels.snapshot.publish(stopped);

  const PointWrite seed{PointId::kExciteSeed, 7.0};
  EXPECT_EQ(gate.submit({&seed, 1}, Requester{"test", true, "", false}).refusal, Refusal::kForbidden);
  const PointWrite crossed[] = {{PointId::kExciteAmplitudeMin, 2.5}, {PointId::kExciteAmplitudeMax, 2.0}};
  const auto r = gate.submit(crossed, kOperator);
  EXPECT_EQ(r.refusal, Refusal::kInvalidValue);
  EXPECT_NE(r.reason.find("amplitude_min_v"), std::string::npos) << r.reason;
  const PointWrite too_long{PointId::kExciteDuration, 120.0};  // the recorder keeps 60 s
  const auto l = gate.submit({&too_long, 1}, kOperator);
  EXPECT_EQ(l.refusal, Refusal::kInvalidValue);
  EXPECT_NE(l.reason.find("[recorder] buffer_s"), std::string::npos) << l.reason;
  EXPECT_TRUE(sink.entries.empty());

  const PointWrite start[] = {{PointId::kMode, 4.0}, {PointId::kExciteSeed, 7.0}, {PointId::kExciteDuration, 20.0}};
  ASSERT_TRUE(gate.submit(start, kOperator).accepted());
  EXPECT_EQ(gate.excitation_settings().seed, 7u);
  EXPECT_EQ(gate.excitation_settings().duration_s, 20.0);
  EXPECT_EQ(gate.excitation_settings().amplitude_max_v, config.excitation.amplitude_max_v);  // the rest kept
  std::vector<runtime::Command> queued;
  runtime::Command c;
  while (channels.commands.try_pop(c)) queued.push_back(c);
  ASSERT_EQ(queued.size(), 2u);  // the settings first, whatever the order of the points
  EXPECT_EQ(queued[0].kind, runtime::CommandKind::kExcitation);
  EXPECT_EQ(queued[0].excitation.seed, 7u);
  EXPECT_EQ(queued[1].kind, runtime::CommandKind::kMode);
  EXPECT_EQ(queued[1].mode, Mode::kExcite);
  EXPECT_EQ(sink.entries.size(), 3u);
}

TEST(WriteGate, ExciteIsEnteredFromStopOnlyWithThePistonBetweenTheGuardLines) {
  const runtime::RuntimeConfig config;
  runtime::LoopChannels channels(16);
  WriteGate gate(limits_of(config), config, paper(), channels, nullptr);
  const PointWrite excite{PointId::kMode, 4.0};
  runtime::Snapshot snap;
  snap.position_mm = 250.0;
  for (Mode mode : {Mode::kRun, Mode::kManual}) {
    snap.mode = mode;
    const auto r = gate.decide({&excite, 1}, kOperator, snap);
    EXPECT_EQ(r.refusal, Refusal::kConflict) << runtime::to_string(mode);
    EXPECT_EQ(modbus_exception(r.refusal), 0x04);
    EXPECT_EQ(http_status(r.refusal), 409);
    EXPECT_NE(r.reason.find("STOP"), std::string::npos) << r.reason;
  }
  snap.mode = Mode::kStop;
  EXPECT_TRUE(gate.decide({&excite, 1}, kOperator, snap).accepted());
  snap.position_mm = 20.0;  // below the lower guard line (-2 + 100 mm)
  const auto low = gate.decide({&excite, 1}, kOperator, snap);
  EXPECT_EQ(low.refusal, Refusal::kConflict);
  EXPECT_NE(low.reason.find("guard"), std::string::npos) << low.reason;
  const PointWrite fault{PointId::kMode, 3.0};
  EXPECT_EQ(gate.decide({&fault, 1}, kOperator, snap).refusal, Refusal::kInvalidValue);  // FAULT is entered by faults only
}

// ---- the gate against the loop: every accept-path ----

// A scan cycle on a fake DAQ in `mode`, with the narrowed configuration.
struct Loop {
  runtime::RuntimeConfig config = narrowed_config();
  runtime::testing::FakeDaq daq;  // 2.0 V: 100 mm, inside every limit
  runtime::VirtualClock clock;
  runtime::LoopChannels channels{64};
  std::unique_ptr<runtime::ScanCycle> loop;
  explicit Loop(Mode mode) {
    if (mode == Mode::kRun) config.start_mode = Mode::kRun;
    if (mode == Mode::kFault) config.start_fault = runtime::FaultCode::kStoreDamaged;
    loop = std::make_unique<runtime::ScanCycle>(config, *runtime::make_tuning(paper()), daq, clock, channels);
    if (mode == Mode::kManual) channels.commands.try_push(runtime::mode_command(Mode::kManual));
    if (mode == Mode::kExcite) {  // from STOP, once a reading placed the piston between the guard lines
      cycle();
      channels.commands.try_push(runtime::mode_command(Mode::kExcite));
    }
    cycle();
  }
  void cycle() {
    loop->cycle(clock.now_ns());
    clock.advance(5'000'000);
  }
};

// Values worth trying for a point: its bounds, the middle, a fraction, just outside, NaN.
std::vector<double> candidates(const PointRange& r) {
  const double lo = r.min.value, hi = r.max.value;
  return {lo, hi, std::floor((lo + hi) / 2), (lo + hi) / 2 + 0.25, lo + 0.5, beyond(lo, -1), beyond(hi, +1),
          std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0, 2.0, 3.0};
}

TEST(WriteGate, EveryWriteTheGateAcceptsIsAppliedByTheScanCycleInTheSameState) {
  const auto config = narrowed_config();
  runtime::LoopChannels gate_channels(16);
  WriteGate gate(limits_of(config), config, paper(), gate_channels, nullptr);
  int accepted = 0, refused = 0;
  auto hold = [&](const std::vector<PointWrite>& writes, Mode mode) {
    Loop l(mode);
    ASSERT_EQ(l.loop->last_snapshot().mode, mode);
    std::vector<runtime::Command> commands;
    const GateResult r = gate.decide(writes, kOperator, l.loop->last_snapshot(), &commands);
    if (!r.accepted()) {
      ++refused;
      EXPECT_FALSE(r.reason.empty());
      return;
    }
    ++accepted;
    const auto before = l.loop->last_snapshot();
    ASSERT_TRUE(l.channels.commands.try_push_all(commands.data(), commands.size()));
    l.cycle();
    const auto after = l.loop->last_snapshot();
    EXPECT_EQ(after.commands_rejected, before.commands_rejected)
        << "the loop refused what the gate accepted in " << runtime::to_string(mode) << ": " << point(writes[0].id).name << " = "
        << writes[0].value << " (" << runtime::describe(after.last_refusal) << ")";
    EXPECT_EQ(after.commands_applied, before.commands_applied + commands.size());
  };
  for (Mode mode : {Mode::kStop, Mode::kRun, Mode::kManual, Mode::kFault, Mode::kExcite}) {
    for (const PointDef* p : gated_points())
      for (double v : candidates(gate.limits().range(p->id))) hold({{p->id, v}}, mode);
    // Groups as HMIs send them: mode and setpoint, a manual move, a whole dead zone.
    hold({{PointId::kMode, 1.0}, {PointId::kSetpoint, 250.0}}, mode);
    hold({{PointId::kMode, 2.0}, {PointId::kManualValve, 1.5}}, mode);
    hold({{PointId::kReset, 1.0}, {PointId::kMode, 1.0}}, mode);  // a fault cleared and RUN asked in one write
    hold({{PointId::kMr, 2.0}, {PointId::kMl, 2.1}, {PointId::kBr, 1.3}, {PointId::kBl, -1.5}, {PointId::kLc, 4.0}}, mode);
    hold({{PointId::kExciteSeed, 7.0}, {PointId::kExciteAmplitudeMax, 2.0}, {PointId::kMode, 4.0}}, mode);
    hold({{PointId::kMode, 0.0}, {PointId::kMode, 4.0}}, mode);
    hold({{PointId::kExciteAmplitudeMin, 2.5}, {PointId::kExciteAmplitudeMax, 2.0}}, mode);  // minimum above maximum
  }
  // Neither side of the check is empty: the walk exercised both.
  EXPECT_GT(accepted, 100);
  EXPECT_GT(refused, 100);
}

TEST(WriteGate, ARefusalThatAroseAfterTheGateLookedIsCountedLoggedAndAuditedAsRefused) {
  const runtime::RuntimeConfig config;
  runtime::testing::FakeDaq daq;
  runtime::VirtualClock clock;
  runtime::LoopChannels channels(64);
  runtime::ScanCycle loop(config, *runtime::make_tuning(paper()), daq, clock, channels);
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  loop.cycle(clock.now_ns());
  const runtime::Snapshot before_fault = channels.snapshot.read();  // STOP
  ASSERT_EQ(before_fault.mode, Mode::kStop);
  // The loop latches a fault; the gate still sees the snapshot of the cycle before (as it would
  // when it reads between the loop's fault and its next publish).
  daq.sensor_v = std::numeric_limits<double>::quiet_NaN();
  clock.advance(5'000'000);
  loop.cycle(clock.now_ns());
  ASSERT_EQ(loop.last_snapshot().mode, Mode::kFault);
  channels.snapshot.publish(before_fault);
  const PointWrite run{PointId::kMode, 1.0};
  ASSERT_TRUE(gate.submit({&run, 1}, Requester{"modbus 10.0.0.5:5020", true, "", false}).accepted());
  ASSERT_EQ(sink.entries.size(), 1u);  // accepted: audited as the change it asked for

  clock.advance(5'000'000);
  loop.cycle(clock.now_ns());
  const runtime::Snapshot s = loop.last_snapshot();
  EXPECT_EQ(s.mode, Mode::kFault);
  EXPECT_EQ(s.commands_rejected, 1u);
  EXPECT_EQ(s.last_refusal, runtime::CommandRefusal::kFaultLatched);

  std::vector<std::string> log;
  gate.take_refusals([&](const std::string& line) { log.push_back(line); });
  ASSERT_EQ(log.size(), 1u);
  EXPECT_NE(log[0].find("refused mode"), std::string::npos) << log[0];
  ASSERT_EQ(sink.entries.size(), 2u);
  const core::AuditEntry& refusal = sink.entries[1];
  EXPECT_EQ(refusal.point, "mode");
  EXPECT_EQ(refusal.old_value, 1.0);  // what was asked ...
  EXPECT_EQ(refusal.new_value, 0.0);  // ... and what the point kept
  EXPECT_NE(refusal.source.find("modbus 10.0.0.5:5020"), std::string::npos) << refusal.source;
  EXPECT_NE(refusal.source.find("fault"), std::string::npos) << refusal.source;
  gate.take_refusals([&](const std::string& line) { log.push_back(line); });
  EXPECT_EQ(log.size(), 1u);  // each refusal once
}

// A loop of record writes from a client with no key wrote 15,442 run files in 20 s: recordings
// are one at a time, record_min_interval_s apart, refused as "not now" in between.
TEST(WriteGate, RecordRequestsArePacedOneAtATime) {
  runtime::RuntimeConfig config = narrowed_config();
  config.record_min_interval_s = 0.3;
  runtime::LoopChannels channels(16);
  channels.snapshot.publish(runtime::Snapshot{});
  RecordingSink sink;
  WriteGate gate(limits_of(config), config, paper(), channels, &sink);
  const PointWrite record{PointId::kRecord, 3600};
  EXPECT_TRUE(gate.submit({&record, 1}, kOperator).accepted());
  const GateResult again = gate.submit({&record, 1}, kOperator);
  EXPECT_EQ(again.refusal, Refusal::kConflict);
  EXPECT_NE(again.reason.find("record_s"), std::string::npos) << again.reason;
  EXPECT_NE(again.reason.find("one at a time"), std::string::npos) << again.reason;
  const PointWrite setpoint{PointId::kSetpoint, 10};
  EXPECT_TRUE(gate.submit({&setpoint, 1}, kOperator).accepted());  // other writes are not paced
  std::this_thread::sleep_for(std::chrono::milliseconds(350));
  EXPECT_TRUE(gate.submit({&record, 1}, kOperator).accepted());
  int records = 0;
  runtime::Command c;
  while (channels.commands.try_pop(c)) records += c.kind == runtime::CommandKind::kRecord;
  EXPECT_EQ(records, 2);
}

}  // namespace
}  // namespace epa::points
