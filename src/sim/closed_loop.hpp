#pragma once
// Closed-loop step runs: a controller against a plant simulator, sample by sample, recorded as
// an epa-run/1 Run with its step metrics. Used by `epa simulate`, the tests and the benchmarks.
//
// Timing (one sample k, period Ts): read the sensor y(k); compute u(k) = controller(r(k), y(k));
// apply u(k) and hold it until k+1; the plant advances to y(k+1). No computation delay is
// modelled: the plant's own q^-1 in B is the one-sample delay of the loop (eq 3 assumes this).
#include <cstdint>
#include <span>

#include "control/controller.hpp"
#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "core/run.hpp"
#include "core/step_metrics.hpp"
#include "sim/valve_line.hpp"

namespace epa::plant {
class PlantSimulator;
}

namespace epa::sim {

struct StepRunOptions {
  double step_mm = 25.0;     // reference applied at k = 0 (docs/paper.md: at rest, y = 0, r applied at k = 0)
  double initial_mm = 0.0;   // piston at rest here
  double duration_s = 20.0;
  double noise_std_mm = 0.0; // seeded Gaussian sensor noise
  std::uint64_t seed = 1;
};

struct StepRun {
  core::Run run;              // t_s, r_mm, y_mm (measured), u_V (applied), uc_V (before compensation)
  core::StepMetrics metrics;  // against the step from initial_mm to initial_mm + step_mm
  std::size_t valve_sign_changes = 0;  // chatter measure over the whole run
  std::size_t faults = 0;               // samples where the controller reported a fault
};

core::Result<StepRun> simulate_step(const core::HammersteinModel& model, const control::ControllerParams& params,
                                    const StepRunOptions& options);

// The same against any plant (the physics plant, a perturbed model) already at rest at
// options.initial_mm with its own noise, through `line` (delay, valve lag). `options.noise_std_mm`
// and `seed` are only recorded: the plant was made with them.
core::Result<StepRun> simulate_step_on(plant::PlantSimulator& plant, double mm_per_volt, const control::ControllerParams& params,
                                       const StepRunOptions& options, const ValveLineOptions& line = {});

// Number of times the sign flips between strictly positive and strictly negative (zeros skipped).
std::size_t count_sign_changes(std::span<const double> values);

// The same over the valve commands of the run's last `seconds` (all of it when shorter): where
// chatter is judged once a move has settled (the pp-traj tables: the last 10 s of a 20 s run).
std::size_t valve_sign_changes_in_last(const StepRun& run, double seconds);

}  // namespace epa::sim
