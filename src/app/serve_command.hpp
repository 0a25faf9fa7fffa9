#pragma once
// `epa serve`: the appliance. Loads config/epa.toml, opens the DAQ backend, runs the scan cycle on
// its own (real-time if allowed) thread, the run recorder on another, and in the main thread
// waits for SIGTERM/SIGINT, logs start-up, mode changes, faults and a periodic status line, and
// talks to systemd (Type=notify: READY, WATCHDOG while the loop advances, STOPPING).
#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

namespace epa::app {

struct ServeOptions {
  std::string config_path = "config/epa.toml";
  std::string hal;            // overrides [hal] backend
  int modbus_io_port = 0;     // overrides [hal.modbus_io] port
  int modbus_port = -1;       // overrides [modbus] port (0: any free port, logged)
  int web_port = -1;          // overrides [web] port (0: any free port, logged)
  std::string mode;           // overrides [startup] mode
  double setpoint_mm = -1.0;  // overrides [startup] setpoint_mm (< 0: not given)
  std::string record_dir;     // overrides [recorder] directory
  std::string db_path;        // overrides [store] path
  double duration_s = 0.0;    // > 0: stop by itself after this long (tests, demos)
};

void add_serve_command(CLI::App& app, ServeOptions& options);
int run_serve(const ServeOptions& options, std::ostream& err);

}  // namespace epa::app
