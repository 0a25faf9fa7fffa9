// 10,000 scan cycles allocate nothing: operator new is replaced for this process and counted
// while the loop runs against the sim plant, with setpoint changes, finished moves and a
// controller switch along the way.
#include <gtest/gtest.h>

#include "../support/counting_new.hpp"
#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "hal/sim_daq.hpp"
#include "runtime/scan_cycle.hpp"

namespace epa::runtime {
namespace {

TEST(RuntimeAllocation, TenThousandScanCyclesAllocateNothing) {
  auto daq = *hal::SimDaq::make(core::paper::model(), {.noise_std_mm = 0.1});
  VirtualClock clock;
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_setpoint_mm = 50.0;
  config.move_window_s = 2.0;
  LoopChannels ch(20000);
  ScanCycle loop(config, *make_tuning(control::paper_controller_config(control::ControllerKind::kPpFfidz)), daq, clock, ch);
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

}  // namespace
}  // namespace epa::runtime
