#pragma once
// `epa serve`: the appliance. Loads config/epa.toml, opens the DAQ backend, runs the scan cycle on
// its own (real-time if allowed) thread, the run recorder on another, and in the main thread
// waits for SIGTERM/SIGINT, logs start-up, mode changes, faults and a periodic status line, and
// talks to systemd (Type=notify: READY, WATCHDOG while the loop advances, STOPPING).
#include <CLI/CLI.hpp>
#include <ostream>
#include <optional>
#include <string>

namespace epa::app {

struct ServeOptions {
  std::string config_path = "config/epa.toml";
  std::string hal;            // overrides [hal] backend
  std::optional<int> modbus_io_port;  // overrides [hal.modbus_io] port
  std::optional<int> modbus_port;     // overrides [modbus] port (0: any free port, logged)
  std::optional<int> web_port;        // overrides [web] port (0: any free port, logged)
  std::string mode;                   // overrides [startup] mode
  std::optional<double> setpoint_mm;  // overrides [startup] setpoint_mm; RUN at start-up then moves there
  std::string record_dir;     // overrides [recorder] directory
  std::string db_path;        // overrides [store] path
  double duration_s = 0.0;    // > 0: stop by itself after this long (tests, demos); exit 4 in FAULT
};

// `serve --duration` whose axis is in FAULT when the time is up exits with this (a signal's stop
// exits 0 whatever the mode).
inline constexpr int kExitEndedInFault = 4;

void add_serve_command(CLI::App& app, ServeOptions& options);
int run_serve(const ServeOptions& options, std::ostream& err);

}  // namespace epa::app
