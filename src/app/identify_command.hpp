#pragma once
// `epa identify`: the paper's two identification steps (section 2.2, 4.1) from run files, without
// MATLAB. The dead zone and the ARX part are fitted together (PSO over the dead zone, least squares
// for the ARX part), then, by default, every parameter is refined on the free-run simulation error
// with the break points kept between the readings of the excitation's ramps (ident/
// simulation_refinement.hpp, ident/ramp_reading.hpp); the ARX order is selected over the given
// ranges with the toolbox's figures (fit %, loss, FPE, AIC), the chosen model is printed next to
// the paper's eq 9-10, written as an
// epa-model/1 file for `epa design --model` and `epa simulate --model`, and drawn against the
// measured validation runs (like the paper's figure 5).
#include <CLI/CLI.hpp>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace epa::app {

struct IdentifyOptions {
  std::vector<std::string> runs;      // estimation runs, epa-run/1
  std::vector<std::string> validate;  // validation runs (not used for estimation)
  std::string na = "1:4", nb = "1:4", nk = "1:2";  // an order or an inclusive range
  std::string out_path;               // epa-model/1; empty: none
  std::string save_name;              // non-empty: save the model under this name into db_path
  std::string db_path = "epa.db";
  std::string plot_path;              // SVG; empty: none
  std::uint64_t seed = 1;
  unsigned particles = 30;
  unsigned generations = 60;
  double m_l = 1.0707;                // normalisation of the dead-zone slopes (the paper's m_l)
  double tolerance_pct = 0.5;         // order rule: fit points from the best that count as equal
  double mm_per_volt = 50.0;          // sensor scale of the model's y
  double stroke_mm = 500.0;           // end stops
  std::string criterion = "simulation";  // or "one-step": the swarm's least-squares fit alone, without the free-run refinement
  double window_s = 0.0;              // simulation criterion: restart from measured y every window_s (0: whole runs)
  std::string break_points = "ramps"; // simulation criterion: "ramps" (within the ramps' band) or "free"
  bool stick_slip = true;             // also fit the stick-slip model (plant/stick_slip_model.hpp)
};

void add_identify_command(CLI::App& app, IdentifyOptions& options);

// Returns the process exit code: 0 on success, 1 on bad input, a failed fit or a failed write.
int run_identify(const IdentifyOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
