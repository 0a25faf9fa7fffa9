// 10,000 scan cycles allocate nothing: operator new is replaced for this process and counted
// while the loop runs against the sim plant, with setpoint changes, finished moves and a
// controller switch along the way; and so does a cycle in EXCITE, from entering it to its end.
#include <gtest/gtest.h>

#include "../support/counting_new.hpp"
#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "hal/sim_daq.hpp"
#include "paper_loop.hpp"
#include "runtime/scan_cycle.hpp"

namespace epa::runtime {
namespace {

using testing::paper_tuning;

TEST(RuntimeAllocation, TenThousandScanCyclesAllocateNothing) {
  auto daq = *hal::SimDaq::make(core::paper::model(), {.noise_std_mm = 0.1});
  VirtualClock clock;
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 50.0;
  config.move_window_s = 2.0;
  LoopChannels ch(20000);
  ScanCycle loop(config, paper_tuning(), daq, clock, ch);
  const Command setpoints[] = {setpoint_command(120.0),
                               controller_command(control::ControllerKind::kPpNgidz),
                               setpoint_command(60.0)};

  const long before = epa::testing::allocation_count();
  for (int k = 0; k < 10000; ++k) {
    if (k % 3000 == 1500) {
      ASSERT_TRUE(ch.commands.try_push(setpoints[(k / 3000) % 3]));
    }
    loop.cycle(clock.now_ns());
    clock.advance(5'000'000);
  }
  const long during = epa::testing::allocation_count() - before;
  EXPECT_EQ(during, 0);
  EXPECT_GE(loop.last_snapshot().moves, 3u);  // the moves finished inside the counted span
  auto* probe = new int(1);                   // and the counter does count
  EXPECT_GT(epa::testing::allocation_count() - before, during);
  delete probe;
}

// Mode EXCITE: entering it (the generator made in place), a whole experiment against the sim
// plant, its end in STOP with the run handed to the recorder, new settings, and a second
// experiment ended by a fault (its event handed to the supervisor's ring): all inside the counted span.
TEST(RuntimeAllocation, AnExcitationExperimentAllocatesNothing) {
  RuntimeConfig config;
  config.excitation.duration_s = 10.0;
  auto sim = *hal::SimDaq::make(core::paper::model(), {.initial_position_mm = 250.0, .noise_std_mm = 0.1});
  struct Failing final : hal::Daq {  // the sim plant, until its reads fail
    hal::Daq& inner;
    bool fail = false;
    explicit Failing(hal::Daq& d) : inner(d) {}
    std::string describe() const override { return "failing"; }
    core::Status open() override { return core::ok(); }
    hal::SensorReading read_sensor() noexcept override {
      return fail ? hal::SensorReading{hal::IoStatus::kError, 0.0} : inner.read_sensor();
    }
    hal::IoStatus write_valve(double v) noexcept override { return inner.write_valve(v); }
    void close() noexcept override {}
  } daq(sim);
  VirtualClock clock;
  LoopChannels ch(record_capacity_samples(config));
  ScanCycle loop(config, paper_tuning(), daq, clock, ch);
  ExcitationSettings next = config.excitation;
  next.seed = 9;
  next.duration_s = 5.0;
  // The first experiment; back to the middle in RUN; new settings and the second experiment in one group.
  const Command first[] = {mode_command(Mode::kExcite)};
  const Command back[] = {setpoint_command(250.0), mode_command(Mode::kRun)};
  const Command second[] = {mode_command(Mode::kStop), excitation_command(next), mode_command(Mode::kExcite)};
  auto cycles = [&](int n) {
    int excite = 0;
    for (int k = 0; k < n; ++k) {
      loop.cycle(clock.now_ns());
      clock.advance(5'000'000);
      excite += loop.last_snapshot().mode == Mode::kExcite ? 1 : 0;
    }
    return excite;
  };

  cycles(1);  // EXCITE needs a position: the first reading
  const long before = epa::testing::allocation_count();
  ASSERT_TRUE(ch.commands.try_push_all(first, 1));
  const int first_excite_cycles = cycles(2100);
  const Mode after_first = loop.last_snapshot().mode;
  ASSERT_TRUE(ch.commands.try_push_all(back, 2));
  cycles(1000);
  ASSERT_TRUE(ch.commands.try_push_all(second, 3));
  cycles(300);
  const Mode during_second = loop.last_snapshot().mode;
  daq.fail = true;  // the second experiment ends in an I/O-error fault
  cycles(5);
  const long during = epa::testing::allocation_count() - before;

  EXPECT_EQ(during, 0);
  EXPECT_EQ(first_excite_cycles, 2000);  // the whole experiment ran inside the counted span
  EXPECT_EQ(after_first, Mode::kStop);
  EXPECT_EQ(during_second, Mode::kExcite);
  EXPECT_EQ(loop.last_snapshot().mode, Mode::kFault);
  EXPECT_EQ(loop.last_snapshot().commands_rejected, 0u);
  RecordRequest r;
  int experiments = 0;
  while (ch.record_requests.try_pop(r)) experiments += r.reason == RecordRequest::Reason::kExcitation ? 1 : 0;
  EXPECT_EQ(experiments, 2);
  FaultEvent fault;  // the fault was handed on inside the counted span too
  ASSERT_TRUE(ch.fault_events.try_pop(fault));
  EXPECT_EQ(fault.code, FaultCode::kIoErrors);
  EXPECT_EQ(fault.mode, Mode::kExcite);
}

}  // namespace
}  // namespace epa::runtime
