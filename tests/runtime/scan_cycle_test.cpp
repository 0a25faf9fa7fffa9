// The scan cycle on the virtual clock: the same code path as `epa simulate`, modes, bumpless
// switching at cycle boundaries, online metrics and the recorder.
#include "runtime/scan_cycle.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"
#include "fake_daq.hpp"
#include "hal/sim_daq.hpp"
#include "plant/plant_adapter.hpp"
#include "runtime/recorder.hpp"
#include "runtime/tuning.hpp"
#include "sim/closed_loop.hpp"
#include "../support/physics_identified_model.hpp"
#include "../support/pp_traj_on_model.hpp"
#include "../support/temp_path.hpp"
#include "core/model_file.hpp"
#include "paper_loop.hpp"

namespace epa::runtime {
namespace {

using testing::kPeriodNs;
using testing::paper_tuning;

using control::ControllerKind;

// Runs `n` cycles at virtual times k * Ts.
void run_cycles(ScanCycle& loop, VirtualClock& clock, int n) {
  for (int k = 0; k < n; ++k) {
    loop.cycle(clock.now_ns());
    clock.advance(kPeriodNs);
  }
}

core::Run recorded(LoopChannels& ch) {
  core::Run run;
  ch.samples.copy_out(0, ch.samples.written(), run);
  return run;
}

TEST(ScanCycle, ReproducesSimulateExactlyForEachController) {
  for (ControllerKind kind : control::kAllControllerKinds) {
    const auto model = core::paper::model();
    auto daq = *hal::SimDaq::make(model, {.noise_std_mm = 0.1, .seed = 5});
    VirtualClock clock;
    RuntimeConfig config;
    config.controller = kind;
    config.start_mode = Mode::kRun;
    config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
    config.start_setpoint_mm = 50.0;
    LoopChannels ch(8000);
    ScanCycle loop(config, paper_tuning(), daq, clock, ch);
    run_cycles(loop, clock, 4000);

    auto params = *control::ControllerParams::make(control::paper_controller_config(kind));
    const auto sim = *sim::simulate_step(model, params, {.step_mm = 50.0, .duration_s = 20.0, .noise_std_mm = 0.1, .seed = 5});
    const core::Run run = recorded(ch);
    ASSERT_EQ(run.size(), sim.run.size());
    EXPECT_EQ(run.y_mm, sim.run.y_mm) << control::to_string(kind);
    EXPECT_EQ(run.u_V, sim.run.u_V) << control::to_string(kind);
    EXPECT_EQ(run.uc_V, sim.run.uc_V) << control::to_string(kind);
    EXPECT_EQ(loop.last_snapshot().mode, Mode::kRun);
  }
}

TEST(ScanCycle, OnlineMoveMetricsAreMoveMetricsOverTheSimulatedSamplesOfTheMove) {
  const auto model = core::paper::model();
  auto daq = *hal::SimDaq::make(model, {});
  VirtualClock clock;
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 100.0;
  config.controller = ControllerKind::kPpNgidz;  // settles into the 1 mm window (FF-IDZ rings on the printed B)
  config.move_window_s = 5.0;
  LoopChannels ch(8000);
  ScanCycle loop(config, paper_tuning(), daq, clock, ch);
  for (int k = 0; k < 1000 && loop.last_snapshot().last_move.number == 0; ++k) run_cycles(loop, clock, 1);
  RecordRequest r;
  ASSERT_TRUE(ch.record_requests.try_pop(r));
  const auto length = static_cast<std::size_t>(r.end - r.first);

  // The loop reproduces `epa simulate` sample for sample: the move's figures are move_metrics over
  // the same samples, its own and no more.
  auto params = *control::ControllerParams::make(control::paper_controller_config(ControllerKind::kPpNgidz));
  const auto sim = *sim::simulate_step(model, params, {.step_mm = 100.0, .duration_s = 5.0});
  ASSERT_LT(length, sim.run.y_mm.size());
  const auto expected = core::move_metrics(std::span(sim.run.y_mm).first(length), 0.0, 100.0, core::MoveEnd::kInPosition,
                                           {.Ts = 0.005, .ess_window_s = config.in_position_time_s});
  const auto& m = loop.last_snapshot().last_move;
  EXPECT_EQ(m.number, 1u);
  EXPECT_EQ(m.end, static_cast<std::uint8_t>(core::MoveEnd::kInPosition));
  EXPECT_EQ(m.from_mm, 0.0);
  EXPECT_EQ(m.to_mm, 100.0);
  EXPECT_EQ(m.controller, ControllerKind::kPpNgidz);
  EXPECT_EQ(m.rise_s, expected.rise_s);
  EXPECT_EQ(m.settling_s, expected.settling_s);
  EXPECT_EQ(m.ess_mm, expected.ess_mm);
  EXPECT_EQ(m.overshoot_pct, expected.overshoot_pct);
  EXPECT_TRUE(std::isfinite(m.rise_s) && std::isfinite(m.settling_s) && std::isfinite(m.overshoot_pct));
  EXPECT_LT(m.ess_mm, config.in_position_window_mm);
  EXPECT_EQ(loop.last_snapshot().moves, 1u);
}

struct Rig {
  testing::FakeDaq daq;
  VirtualClock clock;
  LoopChannels ch{4000};
  RuntimeConfig config;
  std::unique_ptr<ScanCycle> loop;

  explicit Rig(RuntimeConfig c = {}) : config(c) { loop = std::make_unique<ScanCycle>(config, paper_tuning(), daq, clock, ch); }
  void push(Command c) { ASSERT_TRUE(ch.commands.try_push(c)); }
  void cycles(int n) { run_cycles(*loop, clock, n); }
  const Snapshot& snap() const { return loop->last_snapshot(); }
};

TEST(ScanCycle, StopHoldsTheValveSafeAndRunMovesIt) {
  Rig rig;
  rig.cycles(3);
  EXPECT_EQ(rig.daq.last_written_v, 0.0);
  EXPECT_EQ(rig.snap().mode, Mode::kStop);
  rig.push(mode_command(Mode::kRun));  // enable (holds), then the setpoint moves
  rig.push(setpoint_command(150.0));  // 2 V sensor = 100 mm now
  rig.cycles(1);
  EXPECT_EQ(rig.snap().mode, Mode::kRun);
  EXPECT_NE(rig.daq.last_written_v, 0.0);
  rig.push(mode_command(Mode::kStop));
  rig.cycles(1);
  EXPECT_EQ(rig.daq.last_written_v, 0.0);  // within one cycle
}

TEST(ScanCycle, ManualAppliesTheCommandWithinItsLimitAndStartsFromSafe) {
  Rig rig;
  rig.push(manual_valve_command(2.0));
  rig.push(mode_command(Mode::kManual));
  rig.cycles(1);
  EXPECT_EQ(rig.daq.last_written_v, 0.0);  // entering MANUAL never resumes an old command
  rig.push(manual_valve_command(2.0));
  rig.cycles(1);
  EXPECT_EQ(rig.daq.last_written_v, 2.0);
  const auto rejected = rig.snap().commands_rejected;
  rig.push(manual_valve_command(4.0));  // above the 3 V manual limit
  rig.cycles(1);
  EXPECT_EQ(rig.daq.last_written_v, 2.0);
  EXPECT_EQ(rig.snap().commands_rejected, rejected + 1);
}

TEST(ScanCycle, SetpointOutsideTheRangeIsRejectedWhole) {
  Rig rig;
  rig.push(setpoint_command(600.0));
  rig.cycles(1);
  EXPECT_EQ(rig.snap().setpoint_mm, 0.0);
  EXPECT_EQ(rig.snap().commands_rejected, 1u);
}

// Reference: the same law stepped by hand with the state the loop had, so "takes effect at the
// boundary" means: the first cycle after the command uses the new parameters, whole.
TEST(ScanCycle, TuningSwappedMidRunTakesEffectAtTheNextCycleWithTheStateCarriedOver) {
  RuntimeConfig config;
  config.controller = ControllerKind::kPpFfidz;  // the RST history replayed by hand below
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 150.0;
  Rig rig(config);
  rig.daq.sensor_v = 2.0;
  rig.cycles(10);

  auto cfg = control::paper_controller_config(ControllerKind::kPpFfidz);
  cfg.G = {-0.2, 0.6, -0.39};
  Tuning swapped = *make_tuning(cfg);

  // Replay the first 10 cycles by hand to get the state, then one with the new tuning.
  control::ControllerState state;
  state.rst.y_past.fill(2.0);
  state.rst.r_past.fill(2.0);
  const auto old_params = paper_tuning().ffidz;
  for (int k = 0; k < 10; ++k) control::controller_step(old_params, state, 3.0, 2.0);
  const auto expected = control::controller_step(swapped.ffidz, state, 3.0, 2.0);

  const double held_v = rig.daq.last_written_v;
  rig.push(tuning_command(swapped));
  rig.cycles(1);
  EXPECT_DOUBLE_EQ(rig.snap().controller_v, expected.controller_v);
  EXPECT_NE(expected.valve_v, held_v);             // the new tuning asks for another command...
  EXPECT_DOUBLE_EQ(rig.daq.last_written_v, held_v);  // ...which it takes over from the held one (bumpless)
  EXPECT_EQ(rig.snap().tuning.G[0], -0.2);
}

TEST(ScanCycle, ControllerSwitchIsBumplessTheHistoryCarriesOver) {
  RuntimeConfig config;
  config.controller = ControllerKind::kPpFfidz;  // the RST history replayed by hand below
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 150.0;
  Rig rig(config);
  rig.cycles(20);
  control::ControllerState state;
  state.rst.y_past.fill(2.0);
  state.rst.r_past.fill(2.0);
  const auto t = paper_tuning();
  for (int k = 0; k < 20; ++k) control::controller_step(t.ffidz, state, 3.0, 2.0);
  const auto expected = control::controller_step(t.ngidz, state, 3.0, 2.0);
  const double held_v = rig.daq.last_written_v;
  rig.push(controller_command(ControllerKind::kPpNgidz));
  rig.cycles(1);
  EXPECT_EQ(rig.snap().controller, ControllerKind::kPpNgidz);
  EXPECT_DOUBLE_EQ(rig.snap().controller_v, expected.controller_v);  // not restarted from zero
  EXPECT_DOUBLE_EQ(rig.daq.last_written_v, held_v);                  // and the valve does not step
}

// Switching between any two laws while moving makes no step in the valve command; the
// new law takes over within a few time constants and brings the piston to the target. On the
// paper's plant, every ordered pair, switched 80 ms into a 100 mm move.
TEST(ScanCycle, EverySwitchBetweenTwoLawsWhileMovingIsBumpless) {
  for (ControllerKind from : control::kAllControllerKinds) {
    for (ControllerKind to : control::kAllControllerKinds) {
      if (from == to || from == ControllerKind::kPp) continue;  // plain PP stalls in the dead band
      SCOPED_TRACE(std::string(control::to_string(from)) + " -> " + std::string(control::to_string(to)));
      auto daq = *hal::SimDaq::make(core::paper::model(), {.initial_position_mm = 100.0});
      VirtualClock clock;
      RuntimeConfig config;
      config.controller = from;
      config.start_mode = Mode::kRun;
      config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
      config.start_setpoint_mm = 200.0;
      LoopChannels ch(8000);
      ScanCycle loop(config, paper_tuning(), daq, clock, ch);
      run_cycles(loop, clock, 16);
      const double held_v = loop.last_snapshot().valve_v;
      ASSERT_TRUE(ch.commands.try_push(controller_command(to)));
      run_cycles(loop, clock, 1);
      EXPECT_DOUBLE_EQ(loop.last_snapshot().valve_v, held_v);
      EXPECT_EQ(loop.last_snapshot().controller, to);
      run_cycles(loop, clock, 2000);
      if (to != ControllerKind::kPp) {
        EXPECT_NEAR(loop.last_snapshot().position_mm, 200.0, 1.5);
      }
    }
  }
}

// The same on the physics plant (cylinder, valve, stiction): at the switch the valve does not step,
// whichever law hands over to which, moving or holding.
TEST(ScanCycle, SwitchingLawsOnThePhysicsPlantDoesNotStepTheValve) {
  for (int switch_at : {16, 600}) {  // 80 ms into the move, and 3 s later, holding
    for (ControllerKind from : control::kAllControllerKinds) {
      for (ControllerKind to : control::kAllControllerKinds) {
        if (from == to) continue;
        SCOPED_TRACE(std::string(control::to_string(from)) + " -> " + std::string(control::to_string(to)) + " at sample " +
                     std::to_string(switch_at));
        auto plant = plant::make_pneumatic_simulator({}, {.initial_position_mm = 100.0});
        ASSERT_TRUE(plant);
        auto daq = *hal::SimDaq::make(std::move(*plant));
        VirtualClock clock;
        RuntimeConfig config;
        config.controller = from;
        config.start_mode = Mode::kRun;
        config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
        config.start_setpoint_mm = 200.0;
        LoopChannels ch(8000);
        ScanCycle loop(config, paper_tuning(), daq, clock, ch);
        run_cycles(loop, clock, switch_at);
        const double held_v = loop.last_snapshot().valve_v;
        ASSERT_TRUE(ch.commands.try_push(controller_command(to)));
        run_cycles(loop, clock, 1);
        EXPECT_DOUBLE_EQ(loop.last_snapshot().valve_v, held_v);
        run_cycles(loop, clock, 400);
        EXPECT_EQ(loop.last_snapshot().mode, Mode::kRun);  // no fault from the switch
      }
    }
  }
}

// The physics plant (stiction) at 0 mm with 0.1 mm of noise, `law` on the paper's tuning, in RUN
// with a move to 100 mm: a law whose model knows no friction.
struct PhysicsRunTo100 {
  explicit PhysicsRunTo100(ControllerKind law)
      : daq(*hal::SimDaq::make(plant::make_pneumatic_simulator({}, {.initial_position_mm = 0.0, .noise_std_mm = 0.1, .seed = 3}).value())),
        ch(8000) {
    config.controller = law;
    config.start_mode = Mode::kRun;
    config.start_moves_to_setpoint = true;
    config.start_setpoint_mm = 100.0;
    loop = std::make_unique<ScanCycle>(config, paper_tuning(), daq, clock, ch);
  }
  hal::SimDaq daq;
  VirtualClock clock;
  RuntimeConfig config;
  LoopChannels ch;
  std::unique_ptr<ScanCycle> loop;
};

// pp-ngidz with the paper's model hunts on the physics plant's stiction; the loop shows the law's
// hold against it (the axis view's hunting, status bit 13), with the valve centred, until the next
// start or target.
TEST(ScanCycle, AHuntingLawIsHeldAndTheStatusSaysSoUntilTheNextTarget) {
  PhysicsRunTo100 rig(ControllerKind::kPpNgidz);
  auto& [daq, clock, config, ch, loop_ptr] = rig;
  ScanCycle& loop = *loop_ptr;
  int held_at = -1;
  for (int k = 0; k < 4000 && held_at < 0; ++k) {  // 20 s
    run_cycles(loop, clock, 1);
    if (loop.last_snapshot().axis.hunting) held_at = k;
  }
  ASSERT_GE(held_at, 0) << "pp-ngidz without a friction model was expected to hunt here";
  RecordProperty("hunting_held_after_s", std::to_string(held_at * config.period_s));
  run_cycles(loop, clock, 200);
  const Snapshot held = loop.last_snapshot();
  EXPECT_TRUE(held.axis.hunting);
  EXPECT_EQ(held.valve_v, 0.0);
  EXPECT_EQ(held.mode, Mode::kRun);  // a warning (the status word: WebServerTest), never a fault

  // A start to the same target is a new try: the hold is released.
  Command start = control_command(kControlStart);
  start.value = 100.0;
  ASSERT_TRUE(ch.commands.try_push(start));
  run_cycles(loop, clock, 2);
  EXPECT_FALSE(loop.last_snapshot().axis.hunting);
  ASSERT_TRUE(ch.commands.try_push(control_command(0)));
  for (int k = 0; k < 4000 && !loop.last_snapshot().axis.hunting; ++k) run_cycles(loop, clock, 1);
  ASSERT_TRUE(loop.last_snapshot().axis.hunting);  // and hunts again, and is held again
  ASSERT_TRUE(ch.commands.try_push(setpoint_command(150.0)));  // so does a new target
  run_cycles(loop, clock, 2);
  EXPECT_FALSE(loop.last_snapshot().axis.hunting);
}

// pp-traj with the paper's model hunts there too, and then arrives while sliding instead of
// being held: it ends within the in-position window, the status saying neither hunting nor off target.
TEST(ScanCycle, AHuntingPpTrajArrivesWhileSlidingInsteadAndEndsInPosition) {
  PhysicsRunTo100 rig(ControllerKind::kPpTraj);
  auto& [daq, clock, config, ch, loop_ptr] = rig;
  ScanCycle& loop = *loop_ptr;
  bool ever_held = false;
  for (int k = 0; k < 3000; ++k) {  // 15 s
    run_cycles(loop, clock, 1);
    ever_held = ever_held || loop.last_snapshot().axis.hunting;
  }
  const Snapshot end = loop.last_snapshot();
  EXPECT_FALSE(ever_held);
  EXPECT_NEAR(end.position_mm, 100.0, config.in_position_window_mm);
  EXPECT_EQ(end.valve_v, 0.0);
  EXPECT_TRUE(end.axis.in_position);
}

// What pp-traj takes from the loop's rules: its back-off legs within the setpoint range, and the
// in-position window its hunting fallback judges stops against (3/4 of it, when wider than the
// set's own retry band); the set's own band still judges the arrival of a law with a coast, but
// after a short approach (near a travel end), where 3/4 of the window applies too.
TEST(LoopLimits, PpTrajTakesTheSetpointRangeAndTheInPositionWindowFromTheLoop) {
  RuntimeConfig rules;
  rules.setpoint_min_mm = 20.0, rules.setpoint_max_mm = 480.0, rules.in_position_window_mm = 1.0;
  const auto c = with_loop_limits(control::paper_controller_config(ControllerKind::kPpTraj), rules);
  EXPECT_DOUBLE_EQ(c.trajectory.travel_min_v, 20.0 / rules.mm_per_volt);
  EXPECT_DOUBLE_EQ(c.trajectory.travel_max_v, 480.0 / rules.mm_per_volt);
  EXPECT_DOUBLE_EQ(c.trajectory.in_position_window_v, 1.0 / rules.mm_per_volt);
  const auto p = control::ControllerParams::make(c);
  ASSERT_TRUE(p.has_value()) << p.error().message;
  EXPECT_DOUBLE_EQ(p->trajectory().fallback_approach.retry_band_v, 0.75 / rules.mm_per_volt);
  EXPECT_DOUBLE_EQ(p->trajectory().approach.retry_band_v, c.trajectory.retry_band_v);
  EXPECT_DOUBLE_EQ(p->trajectory().approach.short_approach_band_v, 0.75 / rules.mm_per_volt);
  rules.in_position_window_mm = 0.2;  // narrower than the set's band (0.3 mm): the set's band
  const auto narrow = control::ControllerParams::make(with_loop_limits(control::paper_controller_config(ControllerKind::kPpTraj), rules));
  ASSERT_TRUE(narrow.has_value());
  EXPECT_DOUBLE_EQ(narrow->trajectory().fallback_approach.retry_band_v, c.trajectory.retry_band_v);
}

// A position record's side of approach, on an axis whose model says stick-slip (pp-traj arrives
// while sliding): from the near side the move never passes its target; asked from above, the
// piston below the target goes past it and comes down to it.
struct SlidingAxisRun {
  double highest_mm = 0.0, end_mm = 0.0;
};
SlidingAxisRun record_move_on_a_sliding_axis(double approach_direction) {
  auto file = *core::parse_model_toml(epa::testing::kPhysicsIdentifiedModelToml, "identified");
  const auto c = epa::testing::pp_traj_config_on(file);
  auto plant = plant::make_pneumatic_simulator({}, {.initial_position_mm = 100.0});
  auto daq = *hal::SimDaq::make(std::move(*plant));
  VirtualClock clock;
  RuntimeConfig config;
  config.controller = ControllerKind::kPpTraj;
  config.start_mode = Mode::kRun;
  LoopChannels ch(8000);
  ScanCycle loop(config, *make_tuning(c), daq, clock, ch);
  run_cycles(loop, clock, 20);
  Command start = control_command(kControlStart);
  start.value = 150.0;
  start.approach_direction = approach_direction;
  EXPECT_TRUE(ch.commands.try_push(start));
  SlidingAxisRun out;
  for (int k = 0; k < 1600; ++k) {  // 8 s
    run_cycles(loop, clock, 1);
    out.highest_mm = std::max(out.highest_mm, loop.last_snapshot().position_mm);
  }
  out.end_mm = loop.last_snapshot().position_mm;
  return out;
}

TEST(ScanCycle, ARecordsSideOfApproachIsTheSideItsSlidingArrivalComesFrom) {
  const SlidingAxisRun near = record_move_on_a_sliding_axis(0.0);
  EXPECT_LE(near.highest_mm, 151.0) << "from the near side the move passed its target";
  EXPECT_NEAR(near.end_mm, 150.0, 1.0);
  const SlidingAxisRun above = record_move_on_a_sliding_axis(-1.0);
  EXPECT_GT(above.highest_mm, 160.0) << "asked from above, the piston never went above the target";
  EXPECT_NEAR(above.end_mm, 150.0, 1.0);
}

TEST(ScanCycle, ShutDownPutsTheValveSafe) {
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 300.0;
  Rig rig(config);
  rig.cycles(5);
  ASSERT_NE(rig.daq.last_written_v, 0.0);
  rig.loop->shut_down();
  EXPECT_EQ(rig.daq.last_written_v, 0.0);
  EXPECT_EQ(rig.snap().mode, Mode::kStop);
}

TEST(ScanCycle, RunStopsWhenAskedAndLeavesTheValveSafe) {
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 300.0;
  testing::FakeDaq daq;
  VirtualClock clock;
  LoopChannels ch(4000);
  std::atomic<bool> stop{false};
  struct StopAfter final : hal::Daq {  // stops the loop from inside after 100 reads
    testing::FakeDaq& inner; std::atomic<bool>& stop; int reads = 0;
    StopAfter(testing::FakeDaq& d, std::atomic<bool>& s) : inner(d), stop(s) {}
    std::string describe() const override { return "stop-after"; }
    core::Status open() override { return core::ok(); }
    hal::SensorReading read_sensor() noexcept override { if (++reads == 100) stop = true; return inner.read_sensor(); }
    hal::IoStatus write_valve(double v) noexcept override { return inner.write_valve(v); }
    void close() noexcept override {}
  } stopper(daq, stop);
  ScanCycle loop2(config, paper_tuning(), stopper, clock, ch);
  loop2.run(stop);
  EXPECT_EQ(stopper.reads, 100);
  EXPECT_EQ(daq.last_written_v, 0.0);
  EXPECT_EQ(clock.now_ns(), 100 * kPeriodNs);  // absolute deadlines: exactly one period apart
  EXPECT_EQ(loop2.last_snapshot().loop.overruns, 0u);
  EXPECT_EQ(loop2.last_snapshot().loop.cycles, 100u);  // the final statistics are exact, not up to 200 cycles old
}

TEST(Recorder, WritesEachMoveAsAValidRunFile) {
  const test::TempDir dir("recorder");
  auto daq = *hal::SimDaq::make(core::paper::model(), {});
  VirtualClock clock;
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;  // --mode run --setpoint: drive there at start
  config.start_setpoint_mm = 50.0;
  config.move_window_s = 2.0;
  config.controller = ControllerKind::kPpNgidz;
  LoopChannels ch(4000);
  ScanCycle loop(config, paper_tuning(), daq, clock, ch);
  Recorder recorder({.directory = dir.path.string(), .per_move = true, .Ts = 0.005, .source = "test"}, ch);
  run_cycles(loop, clock, 450);
  ASSERT_EQ(recorder.process_pending(), 1u);
  auto run = core::read_run_file(recorder.last_file(), 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  // The move, from its first cycle until it was in position: its last in_position_time_s within
  // the window (the move's metrics are recomputed from this alone: run_history).
  const auto& last = loop.last_snapshot().last_move;
  ASSERT_EQ(last.end, static_cast<std::uint8_t>(core::MoveEnd::kInPosition));
  EXPECT_LT(run->size(), 400u);
  for (std::size_t k = run->size() - 20; k < run->size(); ++k) EXPECT_NEAR(run->y_mm[k], 50.0, config.in_position_window_mm);
  EXPECT_EQ(run->meta("controller"), "pp-ngidz");
  EXPECT_EQ(run->meta("step_mm"), "50");
  EXPECT_EQ(run->meta("target_mm"), "50");
  EXPECT_EQ(run->meta("from_mm"), "0");
  EXPECT_EQ(run->meta("move_end"), "in_position");
  EXPECT_EQ(run->meta("ess_window_s"), "0.1");
  const auto again = core::move_metrics(run->y_mm, 0.0, 50.0, core::MoveEnd::kInPosition, {.Ts = 0.005, .ess_window_s = 0.1});
  EXPECT_NEAR(again.ess_mm, last.ess_mm, 1e-3);
  EXPECT_NEAR(again.rise_s, last.rise_s, 1e-9);
  EXPECT_NEAR(again.settling_s, last.settling_s, 1e-9);
  EXPECT_NEAR(again.overshoot_pct, last.overshoot_pct, 1e-3);
  EXPECT_EQ(run->t_s.front(), 0.0);
  EXPECT_EQ(run->r_mm.front(), 50.0);

  ASSERT_TRUE(ch.commands.try_push(record_command(1.0)));
  run_cycles(loop, clock, 1);
  ASSERT_EQ(recorder.process_pending(), 1u);
  auto requested = core::read_run_file(recorder.last_file(), 0.005);
  ASSERT_TRUE(requested.has_value());
  EXPECT_EQ(requested->size(), 200u);
}

// The model-health monitor's copy of a move: the same samples as its file, after the rest it
// started from, back to rest_before_s but never into the move before it.
TEST(Recorder, HandsOverEachMoveWithTheRestItStartedFrom) {
  const test::TempDir dir("recorder-rest");
  auto daq = *hal::SimDaq::make(core::paper::model(), {});
  VirtualClock clock;
  RuntimeConfig config;
  config.start_mode = Mode::kRun;
  config.start_moves_to_setpoint = true;
  config.start_setpoint_mm = 50.0;
  config.move_window_s = 2.0;
  config.controller = ControllerKind::kPpNgidz;
  LoopChannels ch(4000);
  ScanCycle loop(config, paper_tuning(), daq, clock, ch);
  Recorder recorder({.directory = dir.path.string(), .per_move = true, .Ts = 0.005, .source = "test", .rest_before_s = 1.0}, ch);
  std::vector<core::Run> handed;
  recorder.on_move_with_rest([&](const core::Run& move) { handed.push_back(move); });
  run_cycles(loop, clock, 450);
  ASSERT_EQ(recorder.process_pending(), 1u);
  ASSERT_EQ(handed.size(), 1u);
  run_cycles(loop, clock, 600);  // 3 s at rest
  ASSERT_TRUE(ch.commands.try_push(setpoint_command(100.0)));
  run_cycles(loop, clock, 450);
  ASSERT_EQ(recorder.process_pending(), 1u);
  ASSERT_EQ(handed.size(), 2u);
  auto file = core::read_run_file(recorder.last_file(), 0.005);
  ASSERT_TRUE(file.has_value()) << file.error().message;
  const core::Run& with_rest = handed.back();
  EXPECT_EQ(with_rest.meta("rest_before_samples"), "200");  // 1 s: the rest was longer
  EXPECT_EQ(with_rest.meta("move"), file->meta("move"));
  EXPECT_EQ(with_rest.meta("move_end"), file->meta("move_end"));
  ASSERT_EQ(with_rest.size(), file->size() + 200);
  for (std::size_t k = 0; k < file->size(); ++k) EXPECT_NEAR(with_rest.y_mm[200 + k], file->y_mm[k], 1e-4) << k;
  for (std::size_t k = 0; k < 200; ++k) EXPECT_NEAR(with_rest.y_mm[k], file->y_mm[0], 0.5) << k;  // standing
  EXPECT_EQ(with_rest.t_s.front(), 0.0);

  // A move right after another: its rest goes back to that move's end, not into it.
  ASSERT_TRUE(ch.commands.try_push(setpoint_command(150.0)));
  const auto moves = loop.last_snapshot().last_move.number;
  for (int k = 0; k < 450 && loop.last_snapshot().last_move.number == moves; ++k) run_cycles(loop, clock, 1);
  ASSERT_TRUE(ch.commands.try_push(setpoint_command(200.0)));  // the moment the move to 150 mm ended
  run_cycles(loop, clock, 450);
  ASSERT_EQ(recorder.process_pending(), 2u);
  ASSERT_EQ(handed.size(), 4u);
  const auto rest_samples = std::stoul(handed.back().meta("rest_before_samples"));
  EXPECT_LT(rest_samples, 200u);
  EXPECT_EQ(handed.back().size(), std::stoul(handed.back().meta("rest_before_samples")) + core::read_run_file(recorder.last_file(), 0.005)->size());
}

}  // namespace
}  // namespace epa::runtime
