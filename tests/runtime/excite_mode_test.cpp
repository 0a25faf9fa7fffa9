// Mode EXCITE: the identification experiment of `epa excite` run by the scan cycle itself, on the
// virtual clock, against the paper's plant and a scripted DAQ. It drives the valve within its
// amplitude, ends by itself in STOP with the valve safe, is recorded as an open-loop run, keeps its
// pulses inside the soft limits, is entered from STOP only, and every fault ends it with the valve
// safe in the cycle that finds it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"
#include "fake_daq.hpp"
#include "hal/sim_daq.hpp"
#include "ident/excitation.hpp"
#include "plant/plant_adapter.hpp"
#include "runtime/recorder.hpp"
#include "runtime/scan_cycle.hpp"
#include "../support/temp_path.hpp"
#include "paper_loop.hpp"

namespace epa::runtime {
namespace {

using testing::kPeriodNs;
using testing::kSafeV;
using testing::paper_tuning;
using test::TempDir;

constexpr double kTs = 0.005;

// Remembers the largest |command| the loop wrote, in front of any DAQ.
class Tracking final : public hal::Daq {
 public:
  explicit Tracking(hal::Daq& inner) : inner_(inner) {}
  double max_abs_v = 0.0;
  double last_v = std::numeric_limits<double>::quiet_NaN();
  std::string describe() const override { return "tracking"; }
  core::Status open() override { return core::ok(); }
  hal::SensorReading read_sensor() noexcept override { return inner_.read_sensor(); }
  hal::IoStatus write_valve(double v) noexcept override {
    max_abs_v = std::max(max_abs_v, std::abs(v));
    last_v = v;
    return inner_.write_valve(v);
  }
  void close() noexcept override {}

 private:
  hal::Daq& inner_;
};

// The paper's plant (Hammerstein, 0.1 mm noise) at rest at `start_mm`.
hal::SimDaq paper_plant(double start_mm) {
  return *hal::SimDaq::make(core::paper::model(), {.initial_position_mm = start_mm, .noise_std_mm = 0.1, .seed = 3});
}

// The physics plant (cylinder and valve, 0.1 mm noise) at rest at `start_mm`.
hal::SimDaq physics_plant(double start_mm) {
  return hal::SimDaq::make(plant::make_pneumatic_simulator({}, {.initial_position_mm = start_mm, .noise_std_mm = 0.1, .seed = 3}).value())
      .value();
}

// The scan cycle on a simulated plant, with a recorder.
struct SimRig {
  RuntimeConfig config;
  hal::SimDaq sim;
  Tracking daq{sim};
  VirtualClock clock;
  LoopChannels ch;
  ScanCycle loop;
  TempDir dir;
  Recorder recorder;

  SimRig(RuntimeConfig c, hal::SimDaq plant, const std::string& name)
      : config(c),
        sim(std::move(plant)),
        ch(record_capacity_samples(config)),
        loop(config, paper_tuning(), daq, clock, ch),
        dir(name),
        recorder({.directory = dir.path.string(), .per_move = true, .Ts = kTs, .source = "test"}, ch) {}

  void cycle() {
    loop.cycle(clock.now_ns());
    clock.advance(kPeriodNs);
  }
  // Cycles until the loop leaves EXCITE (at most `limit`); returns how many ran in EXCITE.
  int run_excitation(int limit) {
    int n = 0;
    while (n < limit) {
      cycle();
      if (snap().mode != Mode::kExcite) break;
      ++n;
    }
    return n;
  }
  const Snapshot& snap() const { return loop.last_snapshot(); }
};

RuntimeConfig excite_config(std::uint32_t seed, double amplitude_max_v, double duration_s) {
  RuntimeConfig c;
  c.excitation.seed = seed;
  c.excitation.amplitude_max_v = amplitude_max_v;
  c.excitation.duration_s = duration_s;
  return c;
}

TEST(ExciteMode, DrivesTheValveWithinItsAmplitudeEndsInStopWithTheValveSafeAndIsRecordedOpenLoop) {
  SimRig rig(excite_config(7, 2.5, 10.0), paper_plant(250.0), "complete");
  rig.cycle();
  rig.cycle();
  ASSERT_EQ(rig.snap().mode, Mode::kStop);
  ASSERT_TRUE(rig.ch.commands.try_push(mode_command(Mode::kExcite)));
  rig.cycle();
  ASSERT_EQ(rig.snap().mode, Mode::kExcite);
  EXPECT_NEAR(rig.snap().excitation_left_s, 10.0 - kTs, 1e-9);  // one command of 2000 given

  const int in_excite = 1 + rig.run_excitation(3000);
  EXPECT_EQ(in_excite, 2000);  // 10 s at 5 ms, then STOP by itself in the next cycle
  EXPECT_EQ(rig.snap().mode, Mode::kStop);
  EXPECT_EQ(rig.snap().fault, FaultCode::kNone);
  EXPECT_EQ(rig.daq.last_v, kSafeV);  // in the cycle that ended it
  EXPECT_EQ(rig.snap().excitation_left_s, 0.0);
  EXPECT_LE(rig.daq.max_abs_v, 2.5);
  EXPECT_GT(rig.daq.max_abs_v, 1.3);  // it did drive the valve through and beyond the dead band (b_r 1.232 V)

  // The samples of the experiment are exactly the generator's signal for the positions it read,
  // in soft-limit coordinates.
  core::Run ring;
  rig.ch.samples.copy_out(2, 2002, ring);
  auto generator = *ident::ExcitationGenerator::make(excitation_options(rig.config.excitation, rig.config));
  for (std::size_t k = 0; k < ring.size(); ++k)
    ASSERT_EQ(ring.u_V[k], generator.next(ring.y_mm[k] - rig.config.soft_min_mm)) << "sample " << k;

  ASSERT_EQ(rig.recorder.process_pending(), 1u);
  const std::string file = rig.recorder.last_file();
  EXPECT_NE(file.find("excite-"), std::string::npos) << file;
  EXPECT_NE(file.find("-seed7.csv"), std::string::npos) << file;
  auto run = core::read_run_file(file, kTs);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->size(), 2000u);
  EXPECT_EQ(run->meta("controller"), "open-loop");
  EXPECT_EQ(run->meta("excitation_seed"), "7");
  EXPECT_EQ(run->meta("amplitude_max_V"), "2.5");
  EXPECT_EQ(run->meta("excitation_end"), "complete");
  EXPECT_TRUE(run->r_mm.empty());  // no reference in an open-loop run
  EXPECT_EQ(run->t_s.front(), 0.0);
  ASSERT_EQ(run->u_V.size(), ring.u_V.size());
  for (std::size_t k = 0; k < ring.size(); ++k) ASSERT_NEAR(run->u_V[k], ring.u_V[k], 1e-4) << "sample " << k;  // as written
}

// Soft limits well inside the 500 mm stroke, where the generator's own guard (100 mm from the
// stroke's ends) would let pulses carry the piston onto them.
RuntimeConfig narrow_soft_limits(std::uint32_t seed, double amplitude_max_v) {
  RuntimeConfig c = excite_config(seed, amplitude_max_v, 58.0);
  c.soft_min_mm = 100.0;
  c.soft_max_mm = 400.0;
  c.setpoint_min_mm = 100.0;
  c.setpoint_max_mm = 400.0;
  c.start_setpoint_mm = 250.0;
  c.excitation.guard_mm = 60.0;  // guard lines at 160 and 340 mm
  return c;
}

// A piston without inertia: it moves at 200 mm/s per volt beyond a +-1 V dead band and stops when
// the command does, so any position beyond a guard line is a pulse that was not cut.
class IntegratorDaq final : public hal::Daq {
 public:
  static constexpr double kSpeedMmPerVoltS = 200.0, kDeadBandV = 1.0;
  explicit IntegratorDaq(double start_mm) : y_mm_(start_mm) {}
  std::string describe() const override { return "integrator"; }
  core::Status open() override { return core::ok(); }
  hal::SensorReading read_sensor() noexcept override { return {hal::IoStatus::kOk, y_mm_ / 50.0}; }
  hal::IoStatus write_valve(double v) noexcept override {
    const double drive_v = std::abs(v) > kDeadBandV ? v - std::copysign(kDeadBandV, v) : 0.0;
    y_mm_ += kSpeedMmPerVoltS * drive_v * kTs;
    return hal::IoStatus::kOk;
  }
  void close() noexcept override {}

 private:
  double y_mm_;
};

TEST(ExciteMode, PulsesAreCutAtTheGuardLinesInsideTheSoftLimits) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const RuntimeConfig c = narrow_soft_limits(seed, 5.0);
    const auto valid = validate(c);
    ASSERT_TRUE(valid) << valid.error().message;
    IntegratorDaq plant(250.0);
    Tracking daq(plant);
    VirtualClock clock;
    LoopChannels ch(record_capacity_samples(c));
    ScanCycle loop(c, paper_tuning(), daq, clock, ch);
    auto cycle = [&] {
      loop.cycle(clock.now_ns());
      clock.advance(kPeriodNs);
    };
    cycle();  // EXCITE needs a position: the first reading
    ASSERT_TRUE(ch.commands.try_push(mode_command(Mode::kExcite)));
    do cycle();
    while (loop.last_snapshot().mode == Mode::kExcite);
    EXPECT_EQ(loop.last_snapshot().mode, Mode::kStop) << "seed " << seed;
    EXPECT_EQ(loop.last_snapshot().faults, 0u) << "seed " << seed << ": " << to_string(loop.last_snapshot().fault);

    RecordRequest request;
    ASSERT_TRUE(ch.record_requests.try_pop(request));
    EXPECT_GT(request.pulses_cut, 5u) << "seed " << seed << " (of " << request.pulses << " pulses)";
    core::Run run;
    ch.samples.copy_out(request.first, request.end, run);
    ASSERT_EQ(run.size(), 58u * 200u);
    // A pulse ends in the sample after the piston crossed a guard line: at most one sample of
    // travel at full drive beyond it (the ramps, which come first, stay near the start).
    const double one_sample_mm = IntegratorDaq::kSpeedMmPerVoltS * (5.0 - IntegratorDaq::kDeadBandV) * kTs;
    const auto [lo, hi] = std::minmax_element(run.y_mm.begin(), run.y_mm.end());
    EXPECT_GE(*lo, 160.0 - one_sample_mm) << "seed " << seed;
    EXPECT_LE(*hi, 340.0 + one_sample_mm) << "seed " << seed;
    EXPECT_LT(*lo, 175.0) << "seed " << seed << ": the pulses reached the lower guard line";
    EXPECT_GT(*hi, 325.0) << "seed " << seed << ": the pulses reached the upper guard line";
  }
}

TEST(ExciteMode, ThePhysicsPlantStaysInsideNarrowSoftLimitsWithoutAFault) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    SimRig rig(narrow_soft_limits(seed, 5.0), physics_plant(250.0), "physics" + std::to_string(seed));
    rig.cycle();  // EXCITE needs a position: the first reading
    ASSERT_TRUE(rig.ch.commands.try_push(mode_command(Mode::kExcite)));
    EXPECT_EQ(rig.run_excitation(20000), 58 * 200) << "seed " << seed;
    EXPECT_EQ(rig.snap().mode, Mode::kStop) << "seed " << seed;
    EXPECT_EQ(rig.snap().faults, 0u) << "seed " << seed << ": " << to_string(rig.snap().fault);
    EXPECT_LE(rig.daq.max_abs_v, 5.0);
    ASSERT_EQ(rig.recorder.process_pending(), 1u);
    auto run = core::read_run_file(rig.recorder.last_file(), kTs);
    ASSERT_TRUE(run.has_value()) << run.error().message;
    const auto [lo, hi] = std::minmax_element(run->y_mm.begin(), run->y_mm.end());
    EXPECT_GT(*lo, 100.0) << "seed " << seed;
    EXPECT_LT(*hi, 400.0) << "seed " << seed;
  }
}

// ---- the rules and the faults, on a scripted DAQ ----

struct FakeRig {
  testing::FakeDaq daq;  // 2.0 V: 100 mm, between the guard lines (-2 + 100, 502 - 100)
  VirtualClock clock;
  LoopChannels ch{4000};
  RuntimeConfig config;
  std::unique_ptr<ScanCycle> loop;

  explicit FakeRig(RuntimeConfig c = {}) : config(c) { loop = std::make_unique<ScanCycle>(config, paper_tuning(), daq, clock, ch); }
  void push(Command c) { ASSERT_TRUE(ch.commands.try_push(c)); }
  void cycles(int n) {
    for (int k = 0; k < n; ++k) {
      loop->cycle(clock.now_ns());
      clock.advance(kPeriodNs);
    }
  }
  const Snapshot& snap() const { return loop->last_snapshot(); }
  // The excitation run the loop asked the recorder for, if any.
  std::optional<RecordRequest> excitation_request() {
    RecordRequest r;
    while (ch.record_requests.try_pop(r))
      if (r.reason == RecordRequest::Reason::kExcitation) return r;
    return std::nullopt;
  }
};

TEST(ExciteMode, IsEnteredFromStopOnlyWithThePistonBetweenTheGuardLines) {
  {
    FakeRig rig;
    rig.push(mode_command(Mode::kRun));  // enable (holds), then the setpoint moves
    rig.push(setpoint_command(150.0));
    rig.cycles(2);
    rig.push(mode_command(Mode::kExcite));
    rig.cycles(1);
    EXPECT_EQ(rig.snap().mode, Mode::kRun);
    EXPECT_EQ(rig.snap().last_refusal, CommandRefusal::kNotStopped);
    EXPECT_NE(rig.daq.last_written_v, kSafeV);  // RUN carries on
  }
  {
    FakeRig rig;
    rig.push(mode_command(Mode::kManual));
    rig.push(mode_command(Mode::kExcite));
    rig.cycles(1);
    EXPECT_EQ(rig.snap().mode, Mode::kManual);
    EXPECT_EQ(rig.snap().last_refusal, CommandRefusal::kNotStopped);
  }
  {
    FakeRig rig;
    rig.daq.sensor_v = std::numeric_limits<double>::quiet_NaN();
    rig.cycles(1);
    ASSERT_EQ(rig.snap().mode, Mode::kFault);
    rig.daq.sensor_v = 2.0;
    rig.push(mode_command(Mode::kExcite));
    rig.cycles(1);
    EXPECT_EQ(rig.snap().mode, Mode::kFault);
    EXPECT_EQ(rig.snap().last_refusal, CommandRefusal::kFaultLatched);
  }
  for (double sensor_v : {1.9, 8.1}) {  // 95 and 405 mm: outside the guard lines at 98 and 402 mm
    FakeRig rig;
    rig.daq.sensor_v = sensor_v;
    rig.cycles(1);
    rig.push(mode_command(Mode::kExcite));
    rig.cycles(1);
    EXPECT_EQ(rig.snap().mode, Mode::kStop) << sensor_v;
    EXPECT_EQ(rig.snap().last_refusal, CommandRefusal::kOutsideExcitationGuard) << sensor_v;
    EXPECT_EQ(rig.daq.last_written_v, kSafeV);
  }
  {
    FakeRig rig;
    rig.cycles(1);
    rig.push(mode_command(Mode::kExcite));
    rig.cycles(200);
    EXPECT_EQ(rig.snap().mode, Mode::kExcite);
    EXPECT_NE(rig.daq.last_written_v, kSafeV);  // the first ramp is under way
    rig.push(mode_command(Mode::kExcite));       // already there: nothing changes
    rig.cycles(1);
    EXPECT_EQ(rig.snap().commands_rejected, 0u);
    rig.push(mode_command(Mode::kStop));  // ended by the operator: the valve safe in that cycle
    rig.cycles(1);
    EXPECT_EQ(rig.snap().mode, Mode::kStop);
    EXPECT_EQ(rig.daq.last_written_v, kSafeV);
    const auto request = rig.excitation_request();
    ASSERT_TRUE(request.has_value());
    EXPECT_EQ(request->excitation_end, ExcitationEnd::kStopped);
    EXPECT_TRUE(request->open_loop);
    EXPECT_EQ(request->end - request->first, 201u);
  }
}

// A fault found while the experiment runs: one cycle later the valve is safe, FAULT is latched, and
// what ran is handed to the recorder as an experiment that ended in a fault.
class ExciteFaults : public ::testing::Test {
 protected:
  void start(RuntimeConfig c = {}) {
    c.excitation.amplitude_max_v = 1.5;  // below sensor_frozen_drive_v: the fake reading never moves
    rig_ = std::make_unique<FakeRig>(c);
    rig_->cycles(1);
    rig_->push(mode_command(Mode::kExcite));
    rig_->cycles(20);  // the first ramp: 0.05 V by now
    ASSERT_EQ(rig_->snap().mode, Mode::kExcite);
    ASSERT_NE(rig_->daq.last_written_v, kSafeV);
  }
  void expect_safe_after_one_cycle(FaultCode expected) {
    rig_->cycles(1);
    expect_safe(expected);
  }
  void expect_safe(FaultCode expected) {
    EXPECT_EQ(rig_->daq.last_written_v, kSafeV);
    EXPECT_EQ(rig_->snap().mode, Mode::kFault);
    EXPECT_EQ(rig_->snap().fault, expected) << to_string(rig_->snap().fault);
    const auto request = rig_->excitation_request();
    ASSERT_TRUE(request.has_value());
    EXPECT_EQ(request->excitation_end, ExcitationEnd::kFault);
    EXPECT_EQ(rig_->snap().excitation_left_s, 0.0);
  }
  std::unique_ptr<FakeRig> rig_;
};

TEST_F(ExciteFaults, SensorNotFinite) {
  start();
  rig_->daq.sensor_v = std::numeric_limits<double>::quiet_NaN();
  expect_safe_after_one_cycle(FaultCode::kSensorNotFinite);
}

TEST_F(ExciteFaults, SensorOutOfRange) {
  start();
  rig_->daq.sensor_v = 11.0;
  expect_safe_after_one_cycle(FaultCode::kSensorOutOfRange);
}

TEST_F(ExciteFaults, PositionOutsideTheSoftLimits) {
  start();
  rig_->daq.sensor_v = -0.1;  // -5 mm: a valid reading, beyond soft_min_mm = -2
  expect_safe_after_one_cycle(FaultCode::kSoftLimit);
}

TEST_F(ExciteFaults, ConsecutiveReadErrors) {
  start();
  rig_->daq.read_status = hal::IoStatus::kTimeout;
  const double held = rig_->daq.last_written_v;
  rig_->cycles(2);
  EXPECT_EQ(rig_->snap().mode, Mode::kExcite);
  EXPECT_EQ(rig_->daq.last_written_v, held);  // a missed sample holds the last command
  expect_safe_after_one_cycle(FaultCode::kIoErrors);
}

TEST_F(ExciteFaults, ConsecutiveWriteErrors) {
  start();
  rig_->daq.write_status = hal::IoStatus::kError;
  rig_->cycles(3);  // the third failed write faults at the next cycle's check
  EXPECT_EQ(rig_->snap().mode, Mode::kExcite);
  expect_safe_after_one_cycle(FaultCode::kIoErrors);
}

TEST_F(ExciteFaults, HeartbeatLost) {
  RuntimeConfig c;
  c.heartbeat_timeout_s = 0.2;
  rig_ = std::make_unique<FakeRig>(c);
  rig_->cycles(100);  // STOP does not watch the heartbeat; EXCITE gives a full timeout from its start
  rig_->push(mode_command(Mode::kExcite));
  rig_->cycles(41);  // entered at T; up to T + 200 ms: exactly the timeout, not more
  ASSERT_EQ(rig_->snap().mode, Mode::kExcite);
  ASSERT_NE(rig_->daq.last_written_v, kSafeV);
  expect_safe_after_one_cycle(FaultCode::kHeartbeatLost);
}

TEST_F(ExciteFaults, AReadingThatStopsChangingWhileTheValveDrives) {
  RuntimeConfig c;
  c.excitation.amplitude_max_v = 3.0;
  rig_ = std::make_unique<FakeRig>(c);
  rig_->cycles(1);
  rig_->push(mode_command(Mode::kExcite));
  // The first ramp never sees the piston move, so it climbs past sensor_frozen_drive_v (2 V at 4 s).
  int ran = 0;
  while (rig_->snap().mode == Mode::kExcite || ran == 0) {
    rig_->cycles(1);
    if (++ran > 2000) break;
  }
  EXPECT_GE(ran, 900);  // 4 s to 2 V, then 0.5 s of identical readings
  EXPECT_LE(ran, 910);
  expect_safe(FaultCode::kSensorFrozen);
}

TEST_F(ExciteFaults, RepeatedOverruns) {
  RuntimeConfig c;
  c.max_consecutive_overruns = 3;
  c.excitation.amplitude_max_v = 1.5;
  rig_ = std::make_unique<FakeRig>(c);
  std::atomic<bool> stop{false};
  struct Stopper final : hal::Daq {  // EXCITE after the first cycle, slow reads from the 10th on; stops after 40 writes
    testing::FakeDaq& d;
    std::atomic<bool>& stop;
    LoopChannels& ch;
    Stopper(testing::FakeDaq& dd, std::atomic<bool>& s, LoopChannels& c) : d(dd), stop(s), ch(c) {}
    std::string describe() const override { return ""; }
    core::Status open() override { return core::ok(); }
    hal::SensorReading read_sensor() noexcept override {
      if (d.writes == 10) d.read_takes_ns = 2 * kPeriodNs;  // every cycle from now misses its deadline
      return d.read_sensor();
    }
    hal::IoStatus write_valve(double v) noexcept override {
      if (d.writes == 0) ch.commands.try_push(mode_command(Mode::kExcite));
      if (d.writes > 40) stop = true;
      return d.write_valve(v);
    }
    void close() noexcept override {}
  } stopper(rig_->daq, stop, rig_->ch);
  rig_->daq.clock = &rig_->clock;
  ScanCycle loop(c, paper_tuning(), stopper, rig_->clock, rig_->ch);
  loop.run(stop);
  EXPECT_EQ(loop.last_snapshot().mode, Mode::kFault);
  EXPECT_EQ(loop.last_snapshot().fault, FaultCode::kOverruns);
  EXPECT_EQ(rig_->daq.last_written_v, kSafeV);
  const auto request = rig_->excitation_request();
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->excitation_end, ExcitationEnd::kFault);
}

TEST_F(ExciteFaults, FollowingErrorDoesNotApplyWithoutAController) {
  RuntimeConfig c;
  c.following_error_mm = 20.0;
  c.following_error_time_s = 0.1;
  c.start_setpoint_mm = 400.0;  // 300 mm from the piston, for seconds
  start(c);
  rig_->cycles(400);
  EXPECT_EQ(rig_->snap().mode, Mode::kExcite);
  EXPECT_EQ(rig_->snap().faults, 0u);
}

TEST(ExciteMode, NewSettingsTakeEffectAtTheNextExperimentAndAreCheckedWhole) {
  FakeRig rig;
  ExcitationSettings s = rig.config.excitation;
  s.amplitude_min_v = 2.0;
  s.amplitude_max_v = 1.0;  // minimum above maximum
  rig.push(excitation_command(s));
  rig.cycles(1);
  EXPECT_EQ(rig.snap().last_refusal, CommandRefusal::kExcitationInvalid);
  EXPECT_EQ(rig.snap().excitation.amplitude_max_v, rig.config.excitation.amplitude_max_v);

  s.amplitude_min_v = 0.5;
  s.seed = 42;
  s.duration_s = 2.0;
  rig.push(excitation_command(s));
  rig.push(mode_command(Mode::kExcite));  // one group: the experiment starts with the new settings
  rig.cycles(1);
  EXPECT_EQ(rig.snap().excitation.seed, 42u);
  EXPECT_NEAR(rig.snap().excitation_left_s, 2.0 - kTs, 1e-9);
  s.duration_s = 30.0;
  rig.push(excitation_command(s));  // taken during the experiment, for the next one
  rig.cycles(399);                  // 400 commands (2 s) given
  EXPECT_EQ(rig.snap().mode, Mode::kExcite);
  EXPECT_EQ(rig.snap().excitation.duration_s, 30.0);
  EXPECT_EQ(rig.snap().excitation_left_s, 0.0);
  rig.cycles(1);  // STOP by itself
  EXPECT_EQ(rig.snap().mode, Mode::kStop);
  EXPECT_EQ(rig.daq.last_written_v, kSafeV);
  const auto request = rig.excitation_request();
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->excitation.seed, 42u);
  EXPECT_EQ(request->excitation.duration_s, 2.0);
  EXPECT_EQ(request->excitation_end, ExcitationEnd::kComplete);
}

TEST(ExciteMode, ShutDownEndsTheExperimentWithTheValveSafeAndHandsItToTheRecorder) {
  FakeRig rig;
  rig.cycles(1);
  rig.push(mode_command(Mode::kExcite));
  rig.cycles(100);
  rig.loop->shut_down();
  EXPECT_EQ(rig.daq.last_written_v, kSafeV);
  EXPECT_EQ(rig.snap().mode, Mode::kStop);
  const auto request = rig.excitation_request();
  ASSERT_TRUE(request.has_value());
  EXPECT_EQ(request->excitation_end, ExcitationEnd::kStopped);
}

// ---- recordings: open-loop when no controller drove the samples ----

TEST(Recorder, AManualRecordingIsOpenLoopAndOneThatHoldsRunSamplesNamesTheController) {
  TempDir dir("manual");
  FakeRig rig;
  Recorder recorder({.directory = dir.path.string(), .per_move = false, .Ts = kTs, .source = "test"}, rig.ch);
  rig.push(setpoint_command(100.0));
  rig.push(mode_command(Mode::kRun));
  rig.cycles(100);
  rig.push(mode_command(Mode::kManual));
  rig.push(manual_valve_command(1.0));
  rig.cycles(100);

  rig.push(record_command(0.4));  // 80 samples, all MANUAL
  rig.cycles(1);
  ASSERT_EQ(recorder.process_pending(), 1u);
  auto manual = core::read_run_file(recorder.last_file(), kTs);
  ASSERT_TRUE(manual.has_value()) << manual.error().message;
  EXPECT_EQ(manual->meta("controller"), "open-loop");
  EXPECT_EQ(manual->size(), 80u);
  EXPECT_TRUE(manual->r_mm.empty());
  EXPECT_EQ(manual->u_V.back(), 1.0);

  rig.push(record_command(1.0));  // 200 samples: RUN, then MANUAL
  rig.cycles(1);
  ASSERT_EQ(recorder.process_pending(), 1u);
  auto mixed = core::read_run_file(recorder.last_file(), kTs);
  ASSERT_TRUE(mixed.has_value()) << mixed.error().message;
  EXPECT_EQ(mixed->meta("controller"), "pp-traj");  // the default law
  EXPECT_EQ(mixed->r_mm.size(), mixed->size());
}

}  // namespace
}  // namespace epa::runtime
