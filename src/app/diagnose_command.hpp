#pragma once
// `epa diagnose`: where and why simulated and recorded runs disagree (the sim-to-real gap), which
// unmodelled effect explains it, and how far the gap shrinks once it is added (epa::diag). Writes
// the epa-gap-report/1 JSON (docs/formats.md) and an HTML report with plots.
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>
#include <vector>

namespace epa::app {

struct DiagnoseOptions {
  std::vector<std::string> runs;      // training runs, epa-run/1
  std::vector<std::string> holdout;   // held-out runs; none: cross-validate by run
  std::string model_path;             // epa-model/1; empty: the paper's model
  std::size_t horizon = 10;           // samples between restarts from the measured state
  std::string json_path, report_path;
  std::vector<std::string> effects;   // candidates; empty: all eight
  double stroke_mm = 500.0;
};

void add_diagnose_command(CLI::App& app, DiagnoseOptions& options);
int run_diagnose(const DiagnoseOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
