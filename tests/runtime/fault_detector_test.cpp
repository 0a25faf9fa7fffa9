// The fault checks on their own, without a loop around them: each check names its fault, the
// checks run in their order, and what they count between cycles starts over where it should.
#include "runtime/fault_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

namespace epa::runtime {
namespace {

constexpr std::int64_t kMs = 1'000'000;

// A RUN cycle with a good reading in the middle of the stroke, on target.
CycleView run_cycle(double position_mm = 250.0) {
  return {.mode = Mode::kRun, .read_ok = true, .sensor_v = position_mm / 50.0, .position_mm = position_mm, .valve_v = 0.0,
          .heartbeat_changed_ns = 0, .reference_mm = position_mm, .target_mm = position_mm, .following_position_mm = position_mm};
}

hal::SensorReading good(double sensor_v) { return {hal::IoStatus::kOk, sensor_v}; }
hal::SensorReading failed() { return {hal::IoStatus::kTimeout, 0.0}; }

TEST(FaultDetector, AHealthyCycleFailsNoCheck) {
  FaultDetector d{RuntimeConfig{}};
  d.count_read(good(5.0));
  EXPECT_EQ(d.check(run_cycle(), 0), FaultCode::kNone);
}

TEST(FaultDetector, TheNthFailedReadInARowFaultsAndAGoodOneStartsTheCountOver) {
  RuntimeConfig c;
  c.max_consecutive_io_errors = 3;
  FaultDetector d{c};
  CycleView missed = run_cycle();
  missed.read_ok = false;
  d.count_read(failed());
  d.count_read(failed());
  EXPECT_EQ(d.check(missed, 0), FaultCode::kNone);
  d.count_read(good(5.0));
  d.count_read(failed());
  d.count_read(failed());
  EXPECT_EQ(d.check(missed, 0), FaultCode::kNone);
  d.count_read(failed());
  EXPECT_EQ(d.check(missed, 0), FaultCode::kIoErrors);
  EXPECT_EQ(d.failed_reads(), 3);
  EXPECT_EQ(d.last_read(), hal::IoStatus::kTimeout);
  EXPECT_EQ(d.io_errors(), 5u);
  d.reset();
  EXPECT_EQ(d.check(missed, 0), FaultCode::kNone);
}

TEST(FaultDetector, OverrunsInARowFaultOnlyInARow) {
  RuntimeConfig c;
  c.max_consecutive_overruns = 2;
  FaultDetector d{c};
  d.count_deadline(true);
  d.count_deadline(false);
  d.count_deadline(true);
  EXPECT_EQ(d.check(run_cycle(), 0), FaultCode::kNone);
  d.count_deadline(true);
  EXPECT_EQ(d.check(run_cycle(), 0), FaultCode::kOverruns);
}

TEST(FaultDetector, AnImplausibleReadingFaultsInEveryModeAndBeforeTheAxisChecks) {
  FaultDetector d{RuntimeConfig{}};
  CycleView v = run_cycle(600.0);  // beyond the soft limit too: the reading is named first
  v.mode = Mode::kStop;
  v.sensor_v = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(d.check(v, 0), FaultCode::kSensorNotFinite);
  v.sensor_v = 11.0;
  EXPECT_EQ(d.check(v, 0), FaultCode::kSensorOutOfRange);
  v.mode = Mode::kRun;
  EXPECT_EQ(d.check(v, 0), FaultCode::kSensorOutOfRange);
}

TEST(FaultDetector, AnAxisEnteredOutsideTheSoftLimitsMayComeBackButNotGoFurtherOut) {
  RuntimeConfig c;
  c.soft_max_mm = 502.0;
  FaultDetector d{c};
  EXPECT_EQ(d.check(run_cycle(503.0), 0), FaultCode::kSoftLimit);  // crossed from inside: at once
  d.allow_recovery_from(505.0);
  EXPECT_EQ(d.check(run_cycle(505.5), 0), FaultCode::kNone);   // noise: within 1 mm
  EXPECT_EQ(d.check(run_cycle(504.0), 0), FaultCode::kNone);   // on the way back in
  EXPECT_EQ(d.check(run_cycle(505.5), 0), FaultCode::kSoftLimit);  // 1.5 mm out from 504
  d.allow_recovery_from(505.0);
  EXPECT_EQ(d.check(run_cycle(400.0), 0), FaultCode::kNone);  // inside: the limits hold again
  EXPECT_EQ(d.check(run_cycle(502.5), 0), FaultCode::kSoftLimit);
  EXPECT_TRUE(d.outside_soft_limits(502.5));
  EXPECT_FALSE(d.outside_soft_limits(502.0));
}

TEST(FaultDetector, TheHeartbeatIsLostAfterItsTimeoutWhileTheAxisIsDriven) {
  RuntimeConfig c;
  c.heartbeat_timeout_s = 0.1;
  FaultDetector d{c};
  CycleView v = run_cycle();
  v.heartbeat_changed_ns = 0;
  EXPECT_EQ(d.check(v, 100 * kMs), FaultCode::kNone);
  EXPECT_EQ(d.check(v, 101 * kMs), FaultCode::kHeartbeatLost);
  v.mode = Mode::kStop;
  EXPECT_EQ(d.check(v, 101 * kMs), FaultCode::kNone);
}

TEST(FaultDetector, AReadingThatStandsStillWhileTheValveDrivesFaultsAfterItsTime) {
  RuntimeConfig c;
  c.sensor_frozen_time_s = 0.5;
  c.sensor_frozen_drive_v = 2.0;
  FaultDetector d{c};
  CycleView v = run_cycle();
  v.mode = Mode::kManual;
  v.valve_v = 3.0;
  d.count_read(good(v.sensor_v));
  d.count_read(good(v.sensor_v));  // bit-identical from here
  EXPECT_EQ(d.check(v, 0), FaultCode::kNone);
  EXPECT_EQ(d.check(v, 499 * kMs), FaultCode::kNone);
  EXPECT_EQ(d.check(v, 500 * kMs), FaultCode::kSensorFrozen);
  d.count_read(good(v.sensor_v + 0.001));  // it moved: the time starts over
  EXPECT_EQ(d.check(v, 600 * kMs), FaultCode::kNone);
}

TEST(FaultDetector, AFollowingErrorFaultsAfterItsTimeAndShowsItsBitBefore) {
  RuntimeConfig c;
  c.following_error_mm = 50.0;
  c.following_error_time_s = 1.0;
  FaultDetector d{c};
  d.following().follow_reference(250.0);
  CycleView v = run_cycle();
  v.reference_mm = v.target_mm = 250.0;
  v.following_position_mm = 100.0;  // 150 mm behind
  for (std::int64_t t = 0; t <= 1000 * kMs; t += 5 * kMs) {
    ASSERT_EQ(d.check(v, t), FaultCode::kNone) << t / kMs << " ms";
    EXPECT_EQ(d.following_error_shown(), t >= 200 * kMs) << t / kMs << " ms";  // kFollowingErrorShownAfterS
  }
  EXPECT_EQ(d.check(v, 1010 * kMs), FaultCode::kFollowingError);
  d.restart_following_error();
  EXPECT_FALSE(d.following_error_shown());
  v.mode = Mode::kManual;  // measured in RUN only
  EXPECT_EQ(d.check(v, 3000 * kMs), FaultCode::kNone);
}

}  // namespace
}  // namespace epa::runtime
