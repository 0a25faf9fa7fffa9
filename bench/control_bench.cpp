// Cost of one controller step of each law, one plant step, and a whole 20 s closed-loop run.
// The scan cycle is 5 ms: these figures say how much of it the control core uses.
#include <benchmark/benchmark.h>

#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "plant/hammerstein_plant.hpp"
#include "sim/closed_loop.hpp"

namespace {

using epa::control::ControllerKind;

void BM_ControllerStep(benchmark::State& state) {
  const auto kind = static_cast<ControllerKind>(state.range(0));
  const auto params = *epa::control::ControllerParams::make(epa::control::paper_controller_config(kind));
  epa::control::ControllerState s;
  double y = 0.0;
  for (auto _ : state) {
    const auto out = epa::control::controller_step(params, s, 1.0, y);
    y = 0.999 * y + 1e-4 * out.valve_v;  // keeps a data dependency so the loop is not folded away
    benchmark::DoNotOptimize(y);
  }
  state.SetLabel(std::string(epa::control::to_string(kind)));
}
BENCHMARK(BM_ControllerStep)->Arg(0)->Arg(1)->Arg(2)->Arg(3);

// pp-traj arriving while sliding (control/sliding_approach.hpp), as on an axis with stick-slip.
void BM_ControllerStepSlidingArrival(benchmark::State& state) {
  auto config = epa::control::paper_controller_config(ControllerKind::kPpTraj);
  config.trajectory.coast_s = 0.025;
  const auto params = *epa::control::ControllerParams::make(config);
  epa::control::ControllerState s;
  double y = 0.0;
  for (auto _ : state) {
    const auto out = epa::control::controller_step(params, s, 1.0, y);
    y = 0.999 * y + 1e-4 * out.valve_v;
    benchmark::DoNotOptimize(y);
  }
  state.SetLabel("pp-traj, sliding arrival");
}
BENCHMARK(BM_ControllerStepSlidingArrival);

void BM_PlantStep(benchmark::State& state) {
  auto plant = *epa::plant::HammersteinPlant::make(epa::core::paper::model(), {.initial_position_mm = 250.0, .noise_std_mm = 0.1});
  double u = 2.0;
  for (auto _ : state) {
    plant.step(u);
    u = plant.position_mm() > 250.0 ? -2.5 : 2.0;
    benchmark::DoNotOptimize(u);
  }
}
BENCHMARK(BM_PlantStep);

void BM_ClosedLoop20s(benchmark::State& state) {
  const auto kind = static_cast<ControllerKind>(state.range(0));
  const auto params = *epa::control::ControllerParams::make(epa::control::paper_controller_config(kind));
  const auto model = epa::core::paper::model();
  for (auto _ : state) {
    auto run = epa::sim::simulate_step(model, params, {.step_mm = 100.0, .duration_s = 20.0, .noise_std_mm = 0.1});
    benchmark::DoNotOptimize(run);
  }
  state.SetLabel(std::string(epa::control::to_string(kind)) + ", 4000 samples incl. recording and metrics");
}
BENCHMARK(BM_ClosedLoop20s)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
