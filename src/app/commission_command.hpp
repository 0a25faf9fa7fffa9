#pragma once
// `epa commission`: commissions the axis of a running appliance over its HTTP API (the token is
// the unlock): starts the sequence with a spec, shows its progress, aborts it on Ctrl-C, and
// writes the outcome (epa-commission/1) and the report. Exit status: 0 deployed, 2 rolled back,
// 3 aborted, 1 could not run it (connection, token, a refused spec).
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

namespace epa::app {

struct CommissionOptions {
  std::string url = "http://127.0.0.1:8080";
  std::string token;       // --token or EPA_TOKEN
  std::string token_file;  // --token-file: its first line
  std::string spec_path;    // JSON (commission/commission_spec.hpp); empty: the defaults
  std::string json_path;    // epa-commission/1 of the outcome
  std::string report_path;  // the HTML report
  double poll_s = 0.5;
  double timeout_s = 3600.0;
};

void add_commission_command(CLI::App& app, CommissionOptions& options);
int run_commission(const CommissionOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
