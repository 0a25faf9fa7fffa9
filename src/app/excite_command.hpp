#pragma once
// `epa excite`: the open-loop identification experiment (ident/excitation.hpp: slow ramps through
// the dead band, then multi-level pseudo-random pulses with a position-keeping rule) run against a
// simulated plant (the paper's Hammerstein model or a model file, or with --plant physics the
// pneumatic cylinder and valve of plant/pneumatic_plant.hpp), written as an epa-run/1 file
// (controller=open-loop) for `epa identify`.
//
// On a rig: the signal reads the measured position (pulse signs, ramp turn-around, the guard), so it
// must run in the loop with the plant, not be replayed from a file. Running it on the rig comes with
// `epa serve`'s MANUAL mode in a later issue; until then record an open-loop run on the rig with
// your own tools and save it as epa-run/1 with `# controller=open-loop`.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <ostream>
#include <string>

namespace epa::app {

struct ExciteOptions {
  std::string out_path;         // required: the run file
  std::string model_path;       // empty: the paper's model
  std::string plant = "hammerstein";  // or "physics": the pneumatic cylinder and valve
  std::string physics_config;   // epa-pneumatic/1 for --plant physics; empty: the built-in parameters
  std::string plot_path;        // SVG of the run; empty: none
  double duration_s = 120.0;
  std::uint64_t seed = 1;
  double noise_mm = 0.1;        // sensor noise of the simulated plant
  double amplitude_max_v = 3.0;
  double amplitude_min_v = 0.2;
  double ramp_rate_v_per_s = 0.5;
  double ramp_travel_mm = 40.0;
  double guard_mm = 100.0;
  bool centring = false;  // pulse signs towards the middle instead of sweeps
  int sensor_bits = 0;     // physics: ADC resolution over 0-10 V (0: none)
  int delay_samples = 0;   // physics: transport delay before the spool, samples
};

void add_excite_command(CLI::App& app, ExciteOptions& options);

// Returns the process exit code: 0 on success, 1 on bad input or a failed write (said on `err`).
int run_excite(const ExciteOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
