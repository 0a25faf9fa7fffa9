#include "app/plant_server_command.hpp"

#include <pthread.h>
#include <signal.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <ostream>

#include "app/cli_checks.hpp"
#include "appliance/daq_factory.hpp"
#include "app/module_fault_control.hpp"
#include "appliance/tuning_source.hpp"
#include "core/format.hpp"
#include "plant/plant_adapter.hpp"
#include "rig/remote_io_simulator.hpp"

namespace epa::app {

void add_plant_server_command(CLI::App& app, PlantServerOptions& o) {
  auto* cmd = app.add_subcommand(
      "plant-server", "Run a plant model in real time behind a Modbus TCP server that looks like a remote analog I/O "
                      "module (sensor: input register 0, valve: holding register 0, int16, +-10 V = +-32767)");
  cmd->add_option("--address", o.address, "IPv4 address to listen on (0.0.0.0: all)")->capture_default_str();
  cmd->add_option("--port", o.port, "TCP port (0: any free port)")->capture_default_str()->check(CLI::Range(0, 65535));
  cmd->add_option("--unit-id", o.unit_id, "Modbus unit id served (0xFF is always accepted)")
      ->capture_default_str()->check(CLI::Range(0, 247));
  cmd->add_option("--model", o.model_path, "Model file (epa-model/1 TOML); default: the paper's eq 9-10")
      ->check(CLI::ExistingFile);
  cmd->add_option("--plant", o.plant, "hammerstein (the model) or physics (pneumatic cylinder and valve)")
      ->capture_default_str()->check(CLI::IsMember({"hammerstein", "physics"}));
  cmd->add_option("--physics-config", o.physics_config, "Physics plant parameters (epa-pneumatic/1 TOML); default: built in")
      ->check(CLI::ExistingFile);
  cmd->add_option("--sensor-bits", o.sensor_bits, "Physics plant: ADC resolution over 0-10 V (0: none)")
      ->capture_default_str()->check(CLI::Range(0, 24));
  cmd->add_option("--watchdog-ms", o.watchdog_ms, "Comms watchdog, as remote I/O modules have: centre the valve after this "
                                                 "long without a request (0: off)")
      ->capture_default_str()->check(CLI::Range(0, 60000));
  cmd->add_flag("--control-stdin", o.control_stdin,
                "Fault injection for tests: read 'answers silent|garbage|late MS|normal', 'sensor nan|frozen|fixed V|normal', "
                "'physics KEY VALUE' (physics plant: a key of epa-pneumatic/1, from the next step on) and 'status' lines "
                "on standard input");
  cmd->add_option("--effect", o.effects, "Hammerstein plant: hide an effect in it, e.g. valve_lag=0.02 or static_friction=0.6,0.3 "
                                         "(repeatable; names and parameters as epa diagnose reports them)");
  cmd->add_option("--initial-position", o.initial_position_mm, "Piston position at start, mm")
      ->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--noise", o.noise_mm, "Sensor noise standard deviation, mm")
      ->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--seed", o.seed, "Seed of the sensor noise")->capture_default_str()->check(cli::kSeed);
  cmd->add_option("--realtime-priority", o.realtime_priority,
                  "SCHED_FIFO priority of the simulator's threads, so it answers in bounded time like a module (0: normal)")
      ->capture_default_str()
      ->check(CLI::Range(0, 99));
  cmd->add_flag("--sync-to-valve-writes", o.sync_to_valve_writes,
                "Step the plant half a period after each valve write, as a module with synchronised I/O does (else its "
                "clock runs free, which adds 0 or 1 sample of delay depending on phase)");
  cmd->add_option("--Ts", o.Ts, "Real-time step period, s (default: the model's, 0.005 for the paper)")
      ->check(cli::kPositive);
}

namespace {

// Blocks SIGINT and SIGTERM for as long as it lives, so that sigwait() receives them and the
// threads started meanwhile inherit the block; restores the caller's mask afterwards.
class BlockedStopSignals {
 public:
  BlockedStopSignals() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    ok_ = pthread_sigmask(SIG_BLOCK, &set_, &old_) == 0;
  }
  ~BlockedStopSignals() {
    if (ok_) pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  BlockedStopSignals(const BlockedStopSignals&) = delete;
  BlockedStopSignals& operator=(const BlockedStopSignals&) = delete;

  bool ok() const { return ok_; }
  int wait() const {
    int signal_number = 0;
    while (sigwait(&set_, &signal_number) != 0) {
    }
    return signal_number;
  }

 private:
  sigset_t set_{}, old_{};
  bool ok_ = false;
};

}  // namespace

int run_plant_server(const PlantServerOptions& o, std::ostream& out, std::ostream& err) {
  auto model_file = appliance::load_model(o.model_path);
  if (!model_file) return err << "epa plant-server: " << model_file.error().message << "\n", 1;
  rig::RemoteIoSimulatorConfig config;
  config.address = o.address;
  config.port = o.port;
  config.unit_id = o.unit_id;
  config.model = model_file->model;
  if (o.Ts > 0.0) config.model.Ts = o.Ts;
  config.plant.initial_position_mm = o.initial_position_mm;
  config.plant.noise_std_mm = o.noise_mm;
  config.plant.seed = o.seed;
  config.realtime_priority = o.realtime_priority;
  config.watchdog_ms = o.watchdog_ms;
  config.sync_to_valve_writes = o.sync_to_valve_writes;

  BlockedStopSignals signals;  // before start(): the simulator's threads must not take the signals
  if (!signals.ok()) return err << "epa plant-server: cannot block SIGINT/SIGTERM: " << std::strerror(errno) << "\n", 1;
  core::Result<std::unique_ptr<rig::RemoteIoSimulator>> sim = core::invalid_argument("not started");
  if (o.plant == "physics" && !o.effects.empty())
    return err << "epa plant-server: --effect applies to the hammerstein plant only\n", 1;
  if (o.plant == "physics") {
    auto plant = appliance::make_physics_plant(o.physics_config, {.initial_position_mm = o.initial_position_mm, .initial_pressure_bar = 3.0,
                                                        .noise_std_mm = o.noise_mm, .seed = o.seed,
                                                        .sensor_bits = o.sensor_bits, .Ts = config.model.Ts});
    if (!plant) return err << "epa plant-server: " << plant.error().message << "\n", 1;
    sim = rig::RemoteIoSimulator::start(config, std::move(*plant));
  } else if (!o.effects.empty()) {
    auto effects = plant::parse_effect_specs(o.effects);
    if (!effects) return err << "epa plant-server: --effect: " << effects.error().message << "\n", 1;
    auto plant = plant::make_augmented_simulator(config.model, *effects, config.plant);
    if (!plant) return err << "epa plant-server: " << plant.error().message << "\n", 1;
    sim = rig::RemoteIoSimulator::start(config, std::move(*plant));
  } else {
    sim = rig::RemoteIoSimulator::start(config);
  }
  if (!sim) return err << "epa plant-server: " << sim.error().message << "\n", 1;

  out << "plant-server listening on " << o.address << ":" << (*sim)->port() << " (unit " << o.unit_id << ", Ts "
      << core::format_number(config.model.Ts) << " s)" << std::endl;
  const std::string plant_text = o.plant == "physics"
                                     ? "physics plant (" + (o.physics_config.empty() ? std::string("built-in parameters") : o.physics_config) + ")"
                                     : "model: " + (o.model_path.empty() ? std::string("paper eq 9-10") : o.model_path) +
                                           (o.effects.empty() ? "" : " with hidden effects");
  out << plant_text << "; initial position "
      << core::format_number(o.initial_position_mm) << " mm; sensor noise " << core::format_number(o.noise_mm)
      << " mm; " << (o.sync_to_valve_writes ? "steps synchronised to the valve writes" : "free-running clock")
      << "; stop with SIGINT or SIGTERM" << std::endl;

  std::optional<ModuleFaultControl> control;
  if (o.control_stdin) control.emplace(**sim, out);
  const int signal_number = signals.wait();
  if (control) control->stop();
  (*sim)->stop();
  out << "plant-server stopped by " << (signal_number == SIGINT ? "SIGINT" : "SIGTERM") << " after "
      << (*sim)->steps() << " steps (" << (*sim)->requests() << " requests, " << (*sim)->overruns()
      << " overruns); final position " << core::format_number((*sim)->position_mm()) << " mm" << std::endl;
  return 0;
}

}  // namespace epa::app
