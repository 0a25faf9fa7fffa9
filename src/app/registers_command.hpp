#pragma once
// `epa registers`: validates a register map and exports it for integrators (Markdown, CSV), or
// lists the points a map can bind.
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

namespace epa::app {

struct RegistersOptions {
  std::string map_path = "registers/epa.csv";
  std::string markdown_path;  // "-": standard output
  std::string csv_path;
  bool points = false;
};

void add_registers_command(CLI::App& app, RegistersOptions& options);
int run_registers(const RegistersOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
