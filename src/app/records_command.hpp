#pragma once
// `epa records`: the position-record table of a running appliance over its HTTP API. Without a
// further subcommand it lists the table (GET /api/records, or its JSON with --json);
// `epa records set N --target-mm X ...` writes the fields given of record N in one request
// (POST /api/records: one write-gate group, all or nothing) with the [web] token (--token or
// EPA_TOKEN), then shows the record as the appliance holds it. Exit status 0, or 1 with the reason
// (the appliance's own error text, or the URL that did not answer).
#include <CLI/CLI.hpp>
#include <optional>
#include <ostream>
#include <string>

namespace epa::app {

struct RecordsOptions {
  std::string url = "http://127.0.0.1:8080";
  bool json = false;
  bool set = false;  // `records set` was given
  int record = 0;
  std::optional<double> target_mm, speed_mm_s, window_mm;
  std::optional<std::string> controller;  // a law's name, or "running"
  std::optional<std::string> approach;    // near, from-below, from-above
  std::string token;       // --token or EPA_TOKEN
  std::string token_file;  // --token-file: its first line
};

// Returns the subcommand (main asks it whether it was given).
CLI::App* add_records_command(CLI::App& app, RecordsOptions& options);
int run_records(const RecordsOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
