#pragma once
// `epa faults`: the fault history from the store's file, newest first, each fault with its time,
// cause and what the loop saw (the mode it was in, position, setpoint, valve, sensor). Reads only;
// works while the appliance runs (WAL: a reader never blocks the store thread).
#include <CLI/CLI.hpp>
#include <cstddef>
#include <ostream>
#include <string>

namespace epa::app {

struct FaultsOptions {
  std::string db_path = "epa.db";
  bool json = false;        // the JSON of GET /api/faults instead of a table
  std::size_t limit = 64;   // at most this many (the store keeps 64)
};

// Returns the subcommand (main asks it whether it was given: its name is also a point's).
CLI::App* add_faults_command(CLI::App& app, FaultsOptions& options);
int run_faults(const FaultsOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
