// Every fault drives the valve to its safe command within one cycle, and stays latched until an
// explicit reset; a reset with the cause gone returns to STOP.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "control/paper_controller.hpp"
#include "fake_daq.hpp"
#include "runtime/scan_cycle.hpp"
#include "paper_loop.hpp"

namespace epa::runtime {
namespace {

using testing::kPeriodNs;
using testing::kSafeV;
using testing::paper_tuning;

class Faults : public ::testing::Test {
 protected:
  void start(RuntimeConfig c = {}, bool expect_moving = true) {
    c.start_mode = Mode::kRun;
    c.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
    c.start_setpoint_mm = c.start_setpoint_mm == 0.0 ? 300.0 : c.start_setpoint_mm;
    config_ = c;
    daq_.sensor_v = 2.0;  // 100 mm
    loop_ = std::make_unique<ScanCycle>(c, paper_tuning(), daq_, clock_, ch_);
    cycles(3);
    ASSERT_EQ(snap().mode, Mode::kRun);
    if (expect_moving) { ASSERT_NE(daq_.last_written_v, kSafeV); }  // moving: the valve is open
  }
  void cycles(int n) {
    for (int k = 0; k < n; ++k) {
      loop_->cycle(clock_.now_ns());
      clock_.advance(kPeriodNs);
    }
  }
  // The fault is caused, then exactly one cycle runs: it must already have written the safe command.
  void expect_safe_after_one_cycle(FaultCode expected) {
    cycles(1);
    EXPECT_EQ(daq_.last_written_v, kSafeV);
    EXPECT_EQ(snap().mode, Mode::kFault);
    EXPECT_EQ(snap().fault, expected) << to_string(snap().fault);
  }
  const Snapshot& snap() const { return loop_->last_snapshot(); }

  testing::FakeDaq daq_;
  VirtualClock clock_;
  LoopChannels ch_{4000};
  RuntimeConfig config_;
  std::unique_ptr<ScanCycle> loop_;
};

TEST_F(Faults, SensorNotFinite) {
  start();
  daq_.sensor_v = std::numeric_limits<double>::quiet_NaN();
  expect_safe_after_one_cycle(FaultCode::kSensorNotFinite);
}

TEST_F(Faults, SensorOutOfRange) {
  start();
  daq_.sensor_v = 11.0;
  expect_safe_after_one_cycle(FaultCode::kSensorOutOfRange);
}

TEST_F(Faults, PositionOutsideSoftLimits) {
  RuntimeConfig c;
  c.soft_min_mm = 50.0;
  c.soft_max_mm = 450.0;
  c.setpoint_min_mm = 50.0;
  c.setpoint_max_mm = 450.0;
  start(c);
  daq_.sensor_v = 0.9;  // 45 mm
  expect_safe_after_one_cycle(FaultCode::kSoftLimit);
}

TEST_F(Faults, ConsecutiveReadErrorsFaultOnTheNthFailure) {
  start();  // max_consecutive_io_errors = 3
  daq_.read_status = hal::IoStatus::kTimeout;
  const double held = daq_.last_written_v;
  cycles(2);
  EXPECT_EQ(snap().mode, Mode::kRun);
  EXPECT_EQ(daq_.last_written_v, held);  // a missed sample holds the last command
  expect_safe_after_one_cycle(FaultCode::kIoErrors);
}

TEST_F(Faults, OneMissedReadDoesNotFault) {
  start();
  daq_.read_status = hal::IoStatus::kError;
  cycles(2);
  daq_.read_status = hal::IoStatus::kOk;
  cycles(5);
  EXPECT_EQ(snap().mode, Mode::kRun);
  EXPECT_EQ(snap().io_errors, 2u);
}

TEST_F(Faults, RepeatedOverruns) {
  RuntimeConfig c;
  c.max_consecutive_overruns = 3;
  start(c);
  daq_.clock = &clock_;
  daq_.read_takes_ns = 2 * kPeriodNs;  // every cycle now misses its deadline
  std::atomic<bool> stop{false};
  struct Stopper final : hal::Daq {
    testing::FakeDaq& d; std::atomic<bool>& stop; const Snapshot* snap;
    Stopper(testing::FakeDaq& dd, std::atomic<bool>& s) : d(dd), stop(s), snap(nullptr) {}
    std::string describe() const override { return ""; }
    core::Status open() override { return core::ok(); }
    hal::SensorReading read_sensor() noexcept override { return d.read_sensor(); }
    hal::IoStatus write_valve(double v) noexcept override {
      if (d.writes > 20) stop = true;
      return d.write_valve(v);
    }
    void close() noexcept override {}
  } stopper(daq_, stop);
  ScanCycle loop(c, paper_tuning(), stopper, clock_, ch_);
  loop.run(stop);
  EXPECT_EQ(loop.last_snapshot().mode, Mode::kFault);
  EXPECT_EQ(loop.last_snapshot().fault, FaultCode::kOverruns);
  EXPECT_GE(loop.last_snapshot().loop.overruns, 3u);
  EXPECT_EQ(daq_.last_written_v, kSafeV);
}

TEST_F(Faults, FollowingErrorTooLargeForTooLong) {
  RuntimeConfig c;
  c.following_error_mm = 20.0;
  c.following_error_time_s = 0.5;
  c.sensor_frozen_time_s = 0.0;  // the fake sensor never moves: that is not what this test is about
  start(c);    // a move 100 -> 300 mm with the piston blocked (the fake sensor never moves)
  // The error is against the motion the move is expected to make (pp-traj's plan on the model), not
  // the step to 300 mm: it grows as that motion leaves the piston behind, and passes 20 mm within
  // the first 0.3 s (the plan's acceleration, the law's lag). The status bit shows it once it has
  // lasted kFollowingErrorShownAfterS; the fault's time counts from its start.
  int cycles_to_bit = 0;
  const int shown_after = static_cast<int>(std::lround(kFollowingErrorShownAfterS / 0.005));
  for (; cycles_to_bit < 60 + shown_after && !snap().axis.following_error; ++cycles_to_bit) cycles(1);
  ASSERT_TRUE(snap().axis.following_error) << "a blocked piston lagged less than 20 mm behind the planned motion after 0.3 s";
  EXPECT_GT(cycles_to_bit, shown_after);  // not a step: the planned motion starts where the piston stands
  EXPECT_EQ(snap().mode, Mode::kRun);
  cycles(100 - shown_after);  // 500 ms after the error passed the limit: exactly the allowed time, not more
  EXPECT_EQ(snap().mode, Mode::kRun);
  cycles(1);    // 505 ms
  EXPECT_EQ(snap().mode, Mode::kFault);
  EXPECT_EQ(snap().fault, FaultCode::kFollowingError);
  EXPECT_EQ(daq_.last_written_v, kSafeV);
}

// RUN from the start with the piston outside the soft limits (an axis at its end stop, soft limits
// a few mm inside the stroke): it may be brought back in, as when RUN is entered by command; going
// further out is the fault.
TEST_F(Faults, RunFromTheStartOutsideTheSoftLimitsMayBringThePistonBack) {
  RuntimeConfig c;
  c.soft_min_mm = 102.0, c.setpoint_min_mm = 105.0;  // the fake sensor reads 100 mm: 2 mm outside
  c.start_setpoint_mm = 150.0;
  c.sensor_frozen_time_s = 0.0;  // the fake sensor never moves
  start(c);
  cycles(10);
  EXPECT_EQ(snap().mode, Mode::kRun) << to_string(snap().fault);
  daq_.sensor_v = 98.5 / 50.0;  // 1.5 mm further out than where it started
  expect_safe_after_one_cycle(FaultCode::kSoftLimit);
}

TEST_F(Faults, HeartbeatLostWhenTheClientStopsCounting) {
  RuntimeConfig c;
  c.heartbeat_timeout_s = 0.1;
  c.sensor_frozen_time_s = 0.0;  // the fake sensor never moves: that is not what this test is about
  start(c);
  for (std::uint32_t beat = 1; beat <= 10; ++beat) {  // 10 beats, every 50 ms: no fault
    ASSERT_TRUE(ch_.commands.try_push(heartbeat_command(beat)));
    cycles(10);
  }
  EXPECT_EQ(snap().mode, Mode::kRun);
  ASSERT_TRUE(ch_.commands.try_push(heartbeat_command(11)));
  cycles(1);   // the last change, at time T
  cycles(20);  // up to T + 100 ms: exactly the timeout, not more
  EXPECT_EQ(snap().mode, Mode::kRun);
  cycles(1);   // T + 105 ms
  EXPECT_EQ(snap().mode, Mode::kFault);
  EXPECT_EQ(snap().fault, FaultCode::kHeartbeatLost);
  EXPECT_EQ(daq_.last_written_v, kSafeV);
}

TEST_F(Faults, AReadingThatStopsChangingWhileTheValveDrivesIsAFrozenSensor) {
  RuntimeConfig c;
  c.controller = control::ControllerKind::kPpFfidz;  // the paper's law opens the valve fully at once
  c.sensor_frozen_time_s = 0.5;
  c.following_error_time_s = 0.0;
  start(c);  // RUN to 300 mm from 100 mm: the valve drives hard, the fake reading stays at 2.0 V
  ASSERT_GT(std::abs(daq_.last_written_v), c.sensor_frozen_drive_v);  // driving within the first 3 cycles
  int ran = 3;
  while (snap().mode == Mode::kRun && ran < 400) cycles(1), ++ran;
  // 0.5 s of identical readings under drive: not before 100 cycles, and within 3 more.
  EXPECT_GE(ran, 100);
  EXPECT_LE(ran, 104);
  EXPECT_EQ(snap().mode, Mode::kFault);
  EXPECT_EQ(snap().fault, FaultCode::kSensorFrozen);
  EXPECT_EQ(daq_.last_written_v, kSafeV);
}

TEST_F(Faults, AReadingThatChangesOrAPistonAtRestOrAtAnEndIsNotFrozen) {
  RuntimeConfig c;
  c.sensor_frozen_time_s = 0.5;
  c.following_error_time_s = 0.0;
  start(c);
  for (int k = 0; k < 300; ++k) {  // moving: the reading changes by a count now and then
    daq_.sensor_v += (k % 20 == 0) ? 0.001 : 0.0;
    cycles(1);
  }
  EXPECT_EQ(snap().mode, Mode::kRun);
  c.start_setpoint_mm = 100.0;  // at the setpoint: the valve rests inside the dead band
  start(c, false);
  cycles(300);
  EXPECT_EQ(snap().mode, Mode::kRun);
  c.start_setpoint_mm = 0.5;  // pushing against the end stop at 0 mm: pinned, not frozen
  start(c, false);
  daq_.sensor_v = 0.0;
  cycles(300);
  EXPECT_EQ(snap().fault, FaultCode::kNone);
}

TEST_F(Faults, FaultStaysLatchedUntilResetThenStop) {
  start();
  daq_.sensor_v = 11.0;
  cycles(1);
  ASSERT_EQ(snap().mode, Mode::kFault);
  daq_.sensor_v = 2.0;  // the cause is gone, but the fault stays
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kRun)));
  cycles(5);
  EXPECT_EQ(snap().mode, Mode::kFault);
  EXPECT_EQ(snap().commands_rejected, 1u);
  EXPECT_EQ(daq_.last_written_v, kSafeV);

  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  cycles(1);
  EXPECT_EQ(snap().mode, Mode::kStop);
  EXPECT_EQ(snap().fault, FaultCode::kNone);
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kRun)));
  cycles(1);
  EXPECT_EQ(snap().mode, Mode::kRun);
  EXPECT_EQ(snap().faults, 1u);
}

// After a soft-limit fault and its reset the piston is still outside: RUN or MANUAL may bring it
// back (an integrator found no way to, over Modbus: every enable faulted again at once). Driving
// it further out is the fault again; once inside, crossing out is the fault at once as always.
TEST_F(Faults, AnAxisLeftOutsideTheSoftLimitsCanBeBroughtBackButNotFurtherOut) {
  RuntimeConfig c;
  c.soft_max_mm = 300.0;
  c.setpoint_max_mm = 300.0;
  start(c);
  daq_.sensor_v = 6.04;  // 302 mm: past the limit
  cycles(1);
  ASSERT_EQ(snap().fault, FaultCode::kSoftLimit);
  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  cycles(1);
  ASSERT_EQ(snap().mode, Mode::kStop);
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kManual)));
  cycles(5);
  EXPECT_EQ(snap().mode, Mode::kManual) << "entering MANUAL outside the limit is not a fault";
  daq_.sensor_v = 6.03;  // coming back: 301.5 mm
  cycles(5);
  daq_.sensor_v = 6.06;  // 303 mm: 1.5 mm further out than the innermost point reached
  cycles(1);
  EXPECT_EQ(snap().mode, Mode::kFault);
  EXPECT_EQ(snap().fault, FaultCode::kSoftLimit);

  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  cycles(1);
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kRun)));
  cycles(3);
  EXPECT_EQ(snap().mode, Mode::kRun) << "entering RUN outside the limit holds there";
  daq_.sensor_v = 5.9;  // 295 mm: back inside
  cycles(3);
  daq_.sensor_v = 6.01;  // 300.5 mm: crossing out from inside
  expect_safe_after_one_cycle(FaultCode::kSoftLimit);
}

// The manual valve command ends with MANUAL: after a fault or a mode change it reads back as the
// safe command, not as the 1.5 V an HMI wrote before (an integrator read 1.5 V in STOP).
TEST_F(Faults, TheManualValveCommandEndsWithManual) {
  RuntimeConfig c;
  c.soft_max_mm = 300.0;
  c.setpoint_max_mm = 300.0;
  start(c);
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kManual)));
  ASSERT_TRUE(ch_.commands.try_push(manual_valve_command(1.5)));
  cycles(2);
  ASSERT_EQ(snap().manual_valve_v, 1.5);
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kStop)));
  cycles(1);
  EXPECT_EQ(snap().manual_valve_v, kSafeV) << "after MANUAL -> STOP";
  ASSERT_TRUE(ch_.commands.try_push(mode_command(Mode::kManual)));
  ASSERT_TRUE(ch_.commands.try_push(manual_valve_command(1.5)));
  cycles(2);
  daq_.sensor_v = 6.04;  // past the soft limit: a fault in MANUAL
  cycles(1);
  ASSERT_EQ(snap().mode, Mode::kFault);
  EXPECT_EQ(snap().manual_valve_v, kSafeV) << "after a fault in MANUAL";
}

TEST_F(Faults, ResetWithTheCausePresentFaultsAgain) {
  start();
  daq_.sensor_v = 11.0;
  cycles(1);
  ASSERT_TRUE(ch_.commands.try_push(reset_command()));
  cycles(1);
  EXPECT_EQ(snap().mode, Mode::kFault);  // still out of range: faulted again in the same cycle
  EXPECT_EQ(snap().faults, 2u);
}

}  // namespace
}  // namespace epa::runtime
