#pragma once
// `epa simulate`: closed-loop step runs of the chosen controllers on a plant model, printed next to
// the paper's Table 1, written as epa-run/1 files, epa-sim/1 JSON and an SVG picture.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace epa::app {

struct SimulateOptions {
  std::vector<std::string> controllers = {"pp", "pp-ngidz", "pp-ffidz", "pp-traj"};
  std::vector<double> steps_mm = {25, 50, 100, 200};  // signed: a negative step moves towards 0
  double start_mm = 0.0;      // every run starts at rest here
  std::string plant = "paper";  // paper (the model: the paper's or --model) or physics
  std::string physics_config;   // epa-pneumatic/1 for --plant physics; empty: built in
  // Robustness: the plant differs from the controller's model, or the line to the valve is slow.
  double gain_factor = 1.0;
  double break_point_error_v = 0.0;  // the plant's dead band wider by this on each side
  std::size_t delay_samples = 0;
  double valve_lag_s = 0.0;
  double duration_s = 20.0;
  double Ts = 0.0;           // 0: the model's own
  double lc_mm = 5.0;
  double noise_mm = 0.0;
  int sensor_bits = 0;  // physics: ADC resolution over 0-10 V (0: none)
  std::uint64_t seed = 1;
  std::string model_path;    // empty: the paper's model
  std::string design_path;   // empty: the paper's F, G
  std::string out_dir;       // run files; empty: none
  std::string json_path;     // epa-sim/1; empty: none
  std::string plot_path;     // SVG; empty: none
  double plot_window_s = 3.0;
};

void add_simulate_command(CLI::App& app, SimulateOptions& options);

// Returns the process exit code: 0 on success, 1 on bad input or a failed write (said on `err`).
int run_simulate(const SimulateOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
