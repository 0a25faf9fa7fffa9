#pragma once
// `epa design`: pole-placement design and closed-loop analysis. Without arguments it analyses the
// paper's model and controller (eq 9-13); --T re-solves eq 4 for a given T; --overshoot and
// --settling design T from a spec. Prints a report; --json writes epa-design/1.
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace epa::app {

struct DesignOptions {
  std::string model_path;          // empty: the paper's model
  std::string design_path;         // analyse F, G, H of an epa-design/1 file instead of the paper's
  std::vector<std::string> T;      // "paper" or coefficients of q^0, q^-1, ...
  double overshoot_pct = -1.0;     // < 0: not given
  double settling_s = -1.0;
  double observer_pole = 0.0;
  int input_decimals = 4;          // decimals A, B, T were printed with (for the conditioning warning)
  std::string json_path;
  std::string save_name;           // non-empty: save as a tuning set of this name into db_path
  std::string db_path = "epa.db";
};

void add_design_command(CLI::App& app, DesignOptions& options);
// Exit status: 0; 1 on bad input; 3 when a branch's closed loop is unstable (said last on `err`;
// the JSON is written all the same, for analysis, and --save stores nothing).
int run_design(const DesignOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
