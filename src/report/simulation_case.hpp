#pragma once
// One simulated closed-loop step: which controller, which step, and the run with its metrics.
#include "control/controller_kind.hpp"
#include "sim/closed_loop.hpp"

namespace epa::report {

struct SimulationCase {
  control::ControllerKind kind;
  double step_mm = 0.0;
  sim::StepRun result;
};

}  // namespace epa::report
