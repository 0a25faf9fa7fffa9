#pragma once
// `epa plant-server`: the paper's plant (or any epa-model/1 model) stepped in real time behind a
// Modbus TCP server that looks like a remote analog I/O module (rig::RemoteIoSimulator, default
// register layout: sensor in input register 0, valve in holding register 0, int16, ±10 V =
// ±32767). For hardware-in-the-loop tests of `epa serve` with the modbus-io backend. Runs until
// SIGINT or SIGTERM.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace epa::app {

struct PlantServerOptions {
  std::string address = "127.0.0.1";
  int port = 1502;               // 0: a free port, printed in the "listening" line
  int unit_id = 1;
  std::string model_path;        // empty: the paper's model
  std::string plant = "hammerstein";  // or "physics"
  std::string physics_config;    // epa-pneumatic/1 for --plant physics; empty: the defaults
  int sensor_bits = 0;           // physics: ADC resolution over 0-10 V (0: none)
  int watchdog_ms = 0;           // comms watchdog: valve centred after this long without a request (0: off)
  bool control_stdin = false;    // fault injection commands on standard input (module_fault_control.hpp)
  std::vector<std::string> effects;  // hammerstein: effects hidden in the plant, "valve_lag=0.02"
  double initial_position_mm = 0.0;
  double noise_mm = 0.0;
  std::uint64_t seed = 1;
  double Ts = 0.0;               // 0: the model's own
  int realtime_priority = 0;     // SCHED_FIFO for the simulator's threads (0: normal priority)
  bool sync_to_valve_writes = false;  // step half a period after each valve write (remote_io_simulator.hpp)
};

void add_plant_server_command(CLI::App& app, PlantServerOptions& options);

// Blocks SIGINT and SIGTERM in the calling thread (and so in the simulator's threads) and waits
// for one of them; restores the signal mask before returning. Prints
// "plant-server listening on ADDRESS:PORT (unit N, Ts T s)" on `out` once clients can connect,
// and the final position on exit. Returns 0 after a signal, 1 on bad input or when the port
// cannot be bound (said on `err`).
int run_plant_server(const PlantServerOptions& options, std::ostream& out, std::ostream& err);

}  // namespace epa::app
