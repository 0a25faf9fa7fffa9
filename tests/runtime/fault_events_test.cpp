// A fault reset within one cycle still reaches the supervisor, with its cause. The loop
// runs against a scripted DAQ on a virtual clock; a fault is caused for one cycle and the reset is
// already queued for the next, so no snapshot after that cycle shows it any more. The expected
// values come from the script: the reading the DAQ gave, the calibration (50 mm/V), the setpoint
// and the command the DAQ last received before the fault.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "control/paper_controller.hpp"
#include "fake_daq.hpp"
#include "runtime/scan_cycle.hpp"
#include "paper_loop.hpp"

namespace epa::runtime {
namespace {

using testing::kPeriodNs;
using testing::paper_tuning;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class FaultEvents : public ::testing::Test {
 protected:
  void start(RuntimeConfig c = {}) {
    c.start_mode = Mode::kRun;
    c.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
    c.start_setpoint_mm = 300.0;
    c.soft_min_mm = c.setpoint_min_mm = 50.0;
    c.soft_max_mm = c.setpoint_max_mm = 450.0;
    daq_.sensor_v = 2.0;  // 100 mm at 50 mm/V
    loop_ = std::make_unique<ScanCycle>(c, paper_tuning(), daq_, clock_, ch_);
    cycles(5);
  }
  void cycles(int n) {
    for (int k = 0; k < n; ++k) {
      loop_->cycle(clock_.now_ns());
      clock_.advance(kPeriodNs);
    }
  }
  std::vector<FaultEvent> drain() {
    std::vector<FaultEvent> out;
    FaultEvent e;
    while (ch_.fault_events.try_pop(e)) out.push_back(e);
    return out;
  }
  const Snapshot& snap() const { return loop_->last_snapshot(); }

  testing::FakeDaq daq_;
  VirtualClock clock_;
  LoopChannels ch_{4000};
  std::unique_ptr<ScanCycle> loop_;
};

TEST_F(FaultEvents, AFaultResetInTheNextCycleIsInTheRingWithItsCause) {
  start();
  ASSERT_EQ(snap().mode, Mode::kRun);
  ASSERT_TRUE(drain().empty());
  const double valve_before_v = daq_.last_written_v;  // what the valve was driven with when it happened
  ASSERT_GT(std::abs(valve_before_v), 0.1);            // moving towards 300 mm
  const std::uint64_t cycle = snap().cycle;

  daq_.sensor_v = 11.0;  // out of range for one cycle
  cycles(1);
  ASSERT_EQ(snap().mode, Mode::kFault);
  daq_.sensor_v = 2.0;
  ASSERT_TRUE(ch_.commands.try_push(reset_command()));  // the client's reset, applied at the next cycle's start
  cycles(1);

  // The snapshot no longer knows: this is what the supervisor used to log as "FAULT none".
  EXPECT_EQ(snap().mode, Mode::kStop);
  EXPECT_EQ(snap().fault, FaultCode::kNone);
  EXPECT_EQ(snap().faults, 1u);
  const auto events = drain();
  ASSERT_EQ(events.size(), 1u);
  const FaultEvent& e = events[0];
  EXPECT_EQ(e.code, FaultCode::kSensorOutOfRange);
  EXPECT_EQ(e.mode, Mode::kRun);
  EXPECT_EQ(e.cycle, cycle);
  EXPECT_DOUBLE_EQ(e.loop_time_s, static_cast<double>(cycle) * 0.005);
  EXPECT_DOUBLE_EQ(e.sensor_v, 11.0);
  EXPECT_DOUBLE_EQ(e.position_mm, 550.0);  // the reading, calibrated: the cause
  EXPECT_DOUBLE_EQ(e.setpoint_mm, 300.0);
  EXPECT_DOUBLE_EQ(e.valve_v, valve_before_v);
  EXPECT_EQ(snap().fault_events_dropped, 0u);
}

// io-errors says which exchange failed and how (an outside walk-through had only "the DAQ failed
// to read or write several cycles in a row" when the module's process was killed).
TEST_F(FaultEvents, AnIoFaultSaysWhichExchangesFailedAndHow) {
  start();
  ASSERT_TRUE(drain().empty());
  daq_.read_status = hal::IoStatus::kTimeout;  // the module stops answering
  cycles(3);                                   // the shipped 3 in a row
  ASSERT_EQ(snap().mode, Mode::kFault);
  auto events = drain();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].failed_reads, 3);
  EXPECT_EQ(events[0].last_read, hal::IoStatus::kTimeout);
  const FaultRecord timed_out = fault_record(events[0], 5000);
  EXPECT_EQ(timed_out.text, std::string(describe(FaultCode::kIoErrors)) + ": 3 reads in a row failed, the last timed out (no answer in time)");

  daq_.read_status = hal::IoStatus::kOk;
  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  cycles(1);
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kRun)));
  daq_.write_status = hal::IoStatus::kError;  // the link is down for writes
  cycles(5);
  ASSERT_EQ(snap().mode, Mode::kFault);
  events = drain();
  ASSERT_EQ(events.size(), 1u);
  const FaultRecord refused = fault_record(events[0], 5000);
  EXPECT_EQ(refused.code, FaultCode::kIoErrors);
  EXPECT_NE(refused.text.find("writes in a row failed, the last reported an error"), std::string::npos) << refused.text;
  EXPECT_EQ(refused.text.find("reads"), std::string::npos) << refused.text;
}

TEST_F(FaultEvents, ThreeQuickFaultsInARowGiveThreeEventsInOrder) {
  start();
  const double run_valve_v = daq_.last_written_v;
  // Cycle 1, in RUN: the reading leaves its range.
  daq_.sensor_v = 11.0;
  cycles(1);
  // Cycle 2: the reset takes it to STOP, then the reading is not a number.
  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  daq_.sensor_v = kNaN;
  cycles(1);
  ASSERT_EQ(snap().fault, FaultCode::kSensorNotFinite);
  // Cycle 3: reset and MANUAL in one group; the piston reads 45 mm, below the soft limit of 50.
  const Command reset_then_manual[] = {reset_command(), mode_command(Mode::kManual)};
  ASSERT_TRUE(ch_.commands.try_push_all(reset_then_manual, 2));
  daq_.sensor_v = 0.9;
  cycles(1);
  ASSERT_EQ(snap().fault, FaultCode::kSoftLimit);
  // Cycle 4: reset, and the loop is in STOP as if nothing had happened.
  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  cycles(1);
  EXPECT_EQ(snap().mode, Mode::kStop);
  EXPECT_EQ(snap().fault, FaultCode::kNone);
  EXPECT_EQ(snap().faults, 3u);

  const auto events = drain();
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].code, FaultCode::kSensorOutOfRange);
  EXPECT_EQ(events[0].mode, Mode::kRun);
  EXPECT_DOUBLE_EQ(events[0].position_mm, 550.0);
  EXPECT_DOUBLE_EQ(events[0].valve_v, run_valve_v);
  EXPECT_EQ(events[1].code, FaultCode::kSensorNotFinite);
  EXPECT_EQ(events[1].mode, Mode::kStop);
  EXPECT_TRUE(std::isnan(events[1].sensor_v));
  EXPECT_TRUE(std::isnan(events[1].position_mm));  // calibrated from that reading
  EXPECT_DOUBLE_EQ(events[1].valve_v, 0.0);  // in FAULT the cycle before: the safe command
  EXPECT_EQ(events[2].code, FaultCode::kSoftLimit);
  EXPECT_EQ(events[2].mode, Mode::kManual);
  EXPECT_DOUBLE_EQ(events[2].position_mm, 45.0);
  EXPECT_DOUBLE_EQ(events[2].sensor_v, 0.9);
  EXPECT_DOUBLE_EQ(events[2].setpoint_mm, 300.0);
  EXPECT_EQ(events[1].cycle, events[0].cycle + 1);
  EXPECT_EQ(events[2].cycle, events[1].cycle + 1);
}

TEST_F(FaultEvents, AFullRingDropsTheEventAndCountsIt) {
  start();
  const int faults = static_cast<int>(kFaultEventCapacity) + 5;
  for (int i = 0; i < faults; ++i) {  // a fault every other cycle, nobody draining
    daq_.sensor_v = 11.0;
    cycles(1);
    ASSERT_TRUE(ch_.commands.try_push(reset_command()));
    daq_.sensor_v = 2.0;
    cycles(1);
  }
  EXPECT_EQ(snap().faults, static_cast<std::uint64_t>(faults));
  EXPECT_EQ(snap().fault_events_dropped, 5u);
  EXPECT_EQ(ch_.snapshot.read().fault_events_dropped, 5u);  // published, not only counted
  EXPECT_EQ(drain().size(), kFaultEventCapacity);  // the oldest kept, the newest five dropped
  daq_.sensor_v = 11.0;  // room again
  cycles(1);
  EXPECT_EQ(drain().size(), 1u);
  EXPECT_EQ(snap().fault_events_dropped, 5u);
}

TEST_F(FaultEvents, AFaultLatchedBeforeTheStartIsAnEventWithNothingReadYet) {
  RuntimeConfig c;
  c.start_fault = FaultCode::kStoreDamaged;
  c.start_setpoint_mm = 120.0;
  ScanCycle loop(c, paper_tuning(), daq_, clock_, ch_);
  const auto events = drain();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].code, FaultCode::kStoreDamaged);
  EXPECT_EQ(events[0].mode, Mode::kStop);
  EXPECT_EQ(events[0].cycle, 0u);
  EXPECT_TRUE(std::isnan(events[0].position_mm));
  EXPECT_TRUE(std::isnan(events[0].sensor_v));
  EXPECT_DOUBLE_EQ(events[0].setpoint_mm, 120.0);
  EXPECT_DOUBLE_EQ(events[0].valve_v, c.safe_valve_v);
}

// The supervisor's side: the record it keeps, stamped on the wall clock by how far the loop's
// clock ran since, and the history the interfaces read.
TEST(FaultRecord, StampedByTheLoopTimeSinceTheEvent) {
  FaultEvent e{.cycle = 200, .loop_time_s = 1.0, .code = FaultCode::kHeartbeatLost, .mode = Mode::kManual,
               .position_mm = 120.5, .setpoint_mm = 130.0, .valve_v = 1.5, .sensor_v = 2.41};
  EXPECT_EQ(fault_time_ms(e, 1.035, 1'000'000), 1'000'000 - 35);
  EXPECT_EQ(fault_time_ms(e, 0.99, 1'000'000), 1'000'000);  // a snapshot older than the event: now
  const FaultRecord r = fault_record(e, 5000);
  EXPECT_EQ(r.time_ms, 5000);
  EXPECT_EQ(r.code, FaultCode::kHeartbeatLost);
  EXPECT_EQ(r.mode, Mode::kManual);
  EXPECT_EQ(r.name, "heartbeat-lost");
  EXPECT_EQ(r.text, describe(FaultCode::kHeartbeatLost));
  EXPECT_EQ(r.position_mm, 120.5);
  EXPECT_EQ(r.setpoint_mm, 130.0);
  EXPECT_EQ(r.valve_v, 1.5);
  EXPECT_EQ(r.sensor_v, 2.41);
}

FaultRecord at(std::int64_t time_ms, FaultCode code) {
  FaultRecord r;
  r.time_ms = time_ms;
  r.code = code;
  return r;
}

TEST(FaultHistoryTest, NewestFirstAtMostSixtyFourWithTheTotalCount) {
  FaultHistory h;
  std::vector<FaultRecord> stored;
  for (int i = 0; i < 3; ++i) stored.push_back(at(300 - i * 100, FaultCode::kSoftLimit));
  h.load(stored, 10);  // the store kept 3 of the 10 faults it recorded (a fault history trimmed elsewhere)
  EXPECT_EQ(h.total(), 10u);
  EXPECT_EQ(h.newest().front().time_ms, 300);
  for (int i = 0; i < 70; ++i) h.add(at(1000 + i, FaultCode::kHeartbeatLost));
  std::uint64_t total = 0;
  const auto all = h.newest(1000, &total);
  EXPECT_EQ(total, 80u);
  ASSERT_EQ(all.size(), 64u);
  EXPECT_EQ(all.front().time_ms, 1069);  // newest first
  EXPECT_EQ(all.back().time_ms, 1006);
  EXPECT_EQ(h.newest(2).size(), 2u);

  std::array<FaultRecord, 3> few{};
  FaultHistory empty;
  EXPECT_EQ(empty.copy_newest(few), 0u);
  for (const auto& r : few) {
    EXPECT_EQ(r.code, FaultCode::kNone);
    EXPECT_TRUE(std::isnan(r.position_mm));
  }
  EXPECT_EQ(h.copy_newest(few), 80u);
  EXPECT_EQ(few[0].time_ms, 1069);
  EXPECT_EQ(few[2].time_ms, 1067);
}

// A reader never sees the history behind the loop: each read first takes in what is pending
// (serve's intake drains the loop's fault ring), so a fault reset within a cycle is already there
// when the client that saw it latch asks.
TEST(FaultHistoryTest, EveryReadTakesInThePendingFaultsFirst) {
  FaultHistory h;
  int pending = 2;
  h.set_intake([&] {
    for (; pending > 0; --pending) h.add(at(500 + pending, FaultCode::kSoftLimit));
  });
  EXPECT_EQ(h.total(), 2u);
  pending = 1;
  std::array<FaultRecord, 2> newest{};
  EXPECT_EQ(h.copy_newest(newest), 3u);
  EXPECT_EQ(newest[0].time_ms, 501);
  pending = 1;
  std::uint64_t total = 0;
  EXPECT_EQ(h.newest(10, &total).size(), 4u);
  EXPECT_EQ(total, 4u);
}

}  // namespace
}  // namespace epa::runtime
