// The whole commissioning sequence, offline, on the physics rig of tests/integration/commission_test.py
// (physics_rig_commissioning.hpp) through a remote I/O path whose commands reach the valve a cycle
// late with a given probability, over sensor-noise seeds: a deploy rate (bench/commission_physics.sh).
//
//   commission_physics_sweep [--seeds N] [--first S] [--late P,P,...] [--keep DIR]
//
// One line per run (seed, lateness, verdict, reason, the identification's summary), then a table:
// runs deployed per lateness, and the failures by where they stopped. --keep writes each failed
// run's epa-commission/1 JSON, its experiment and its axis moves (epa-run/1 CSV), and the positions
// of each simulated move that failed (one per line, mm), into DIR.
// Exit 0 when every run ended (whatever its verdict), 1 on a usage or harness error.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include "core/run_file.hpp"
#include "physics_rig_commissioning.hpp"

using namespace epa;

namespace {

void keep(const std::filesystem::path& dir, const std::string& name, const commission::CommissionOutcome& out) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / (name + ".json")) << commission::format_commission_json(out);
  for (std::size_t i = 0; i < out.experiment.size(); ++i) {
    std::ofstream f(dir / (name + "-excitation" + std::to_string(i + 1) + ".csv"));
    core::write_run(f, out.experiment[i]);
  }
  if (out.simulation)  // each failed simulated move's positions, one per sample, mm
    for (std::size_t c = 0; c < out.simulation->cases.size(); ++c)
      for (std::size_t i = 0; i < out.simulation->cases[c].moves.size(); ++i) {
        if (out.simulation->cases[c].moves[i].passed) continue;
        std::ofstream f(dir / (name + "-simulated-case" + std::to_string(c + 1) + "-move" + std::to_string(i + 1) + ".txt"));
        for (double y : out.simulation->cases[c].positions_mm[i]) f << y << "\n";
      }
  for (std::size_t i = 0; i < out.measured_moves.size(); ++i) {
    std::ofstream f(dir / (name + "-move" + std::to_string(i + 1) + ".csv"));
    core::write_run(f, out.measured_moves[i]);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Commissioning on the physics rig through a late-command I/O path, over seeds"};
  int seeds = 10;
  int first = 1;
  std::vector<double> lates = {0.0, 0.3, 0.5};
  std::string keep_dir;
  app.add_option("--seeds", seeds, "Sensor-noise seeds per lateness")->capture_default_str()->check(CLI::Range(1, 10000));
  app.add_option("--first", first, "First seed")->capture_default_str()->check(CLI::NonNegativeNumber);
  app.add_option("--late", lates, "Probabilities that a command reaches the valve a cycle late")->delimiter(',')->check(CLI::Range(0.0, 1.0));
  app.add_option("--keep", keep_dir, "Write each failed run's outcome, experiment and moves here");
  CLI11_PARSE(app, argc, argv);

  std::map<double, std::pair<int, int>> deployed_of;  // lateness -> (deployed, runs)
  std::map<std::string, int> failures_by_stage;
  for (double late : lates)
    for (int seed = first; seed < first + seeds; ++seed) {
      const auto run = testing::commission_physics_rig(static_cast<std::uint64_t>(seed), late);
      if (!run) return std::cerr << "commission_physics_sweep: " << run.error().message << "\n", 1;
      const auto& out = *run;
      const bool deployed = out.verdict == commission::Verdict::kDeployed;
      auto& [ok, runs] = deployed_of[late];
      ok += deployed, ++runs;
      if (!deployed) ++failures_by_stage[std::string(commission::to_string(out.failed_stage))];
      std::printf("seed %d late %.2f: %s: %s\n  %s\n", seed, late, std::string(to_string(out.verdict)).c_str(), out.reason.c_str(),
                  out.identified ? out.identified->summary.c_str() : "(no model)");
      std::fflush(stdout);
      if (!deployed && !keep_dir.empty()) {
        char name[64];
        std::snprintf(name, sizeof name, "seed%d-late%.2f", seed, late);
        keep(keep_dir, name, out);
      }
    }
  std::printf("\n| late commands | deployed |\n| --- | --- |\n");
  for (const auto& [late, counts] : deployed_of) std::printf("| %.0f %% | %d/%d |\n", 100.0 * late, counts.first, counts.second);
  std::printf("\nfailed at:");
  for (const auto& [stage, n] : failures_by_stage) std::printf(" %s %d", stage.c_str(), n);
  int ok = 0, runs = 0;
  for (const auto& [late, counts] : deployed_of) ok += counts.first, runs += counts.second;
  std::printf("%s\ndeployed %d/%d\n", failures_by_stage.empty() ? " nothing" : "", ok, runs);
  return 0;
}
