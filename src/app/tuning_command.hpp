#pragma once
// `epa tuning`: the tuning store from the command line. list, show, diff two sets, activate,
// export to and import from an epa-tuning/1 TOML file, the audit log with filters, and the run
// history. Activation and imports are audited (source "cli"); a running appliance keeps the set it
// started with until it is restarted.
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

namespace epa::app {

struct TuningOptions {
  std::string db_path = "epa.db";
  std::string set, other;    // show/export/activate: set; diff: set and other
  std::string file;          // export --out / import FILE
  std::string name;          // import --name
  bool activate = false;     // import --activate
  std::string since, until;  // audit: ISO 8601 UTC (YYYY-MM-DD or YYYY-MM-DDThh:mm:ssZ) or unix ms
  std::string source, point;
  std::size_t limit = 100;
  bool json = false;
};

void add_tuning_command(CLI::App& app, TuningOptions& options);
int run_tuning(CLI::App& app, const TuningOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
