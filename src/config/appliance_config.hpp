#pragma once
// config/epa.toml (epa-config/1): everything `epa serve` needs, read into the runtime's and the
// backends' own config structs. Every key is optional (defaults as in config/epa.toml), every
// value is type- and range-checked, and unknown keys are refused; messages name the file, the
// line and the key. Relative paths of files the configuration names (model, design, register map,
// the status page's static files) are resolved against the configuration file's folder; the
// appliance's data (the store's database, the recorder's directory) against the working directory
// (/var/lib/epa under systemd).
#include <string>

#include "diag/model_health.hpp"
#include "hal/comedi_daq.hpp"
#include "hal/modbus_io_daq.hpp"
#include "modbus/modbus_server.hpp"
#include "plant/hammerstein_plant.hpp"
#include "hal/realtime.hpp"
#include "runtime/recorder.hpp"
#include "runtime/runtime_config.hpp"
#include "web/web_server.hpp"

namespace epa::config {

enum class HalBackend { kSim, kModbusIo, kComedi };

// [health]: the model-health monitor (appliance/health_monitor.hpp).
struct HealthSettings {
  bool enabled = true;
  double stroke_mm = 500.0;     // the end stops (0 and this): segments of a move that reach them are not judged
  diag::HealthConfig estimator;  // its baseline, window and thresholds
};

struct ApplianceConfig {
  runtime::RuntimeConfig runtime;
  hal::RealtimeRequest realtime;

  std::string model_path;   // "": the paper's model
  std::string design_path;  // "": the paper's F, G
  double lc_mm = 5.0;
  double valve_limit_v = 5.0;

  std::string store_path = "epa.db";  // the tuning store (SQLite), relative to the working directory
  std::string record_directory = "runs";
  bool record_per_move = true;
  double record_quota_mb = 512;            // [recorder] quota_mb: the run files' total, the oldest deleted beyond it
  double record_move_files_per_minute = 60;  // [recorder] move_files_per_minute: more moves are not written
  double store_min_free_mb = 256;          // [store] min_free_mb: below it, no run files and a warning
  std::int64_t audit_max_rows = 1'000'000;  // [store] audit_max_rows: the audit log's newest rows kept
  double status_interval_s = 10.0;

  HealthSettings health;

  modbus::ServerConfig modbus;  // [modbus] (plain_enabled: its enabled) and [modbus_tls] (secure)
  std::string register_map_path = "../registers/epa.csv";  // relative to the configuration file

  bool web_enabled = true;
  web::WebConfig web;  // static_dir relative to the configuration file

  HalBackend backend = HalBackend::kSim;
  plant::PlantOptions sim;
  std::string sim_plant = "hammerstein";  // [hal.sim] plant: "hammerstein" (the model) or "physics"
  std::string physics_config;             // [hal.sim] physics_config: epa-pneumatic/1; "": the defaults
  int sim_sensor_bits = 0;                // [hal.sim] sensor_bits (physics): ADC resolution, 0: none
  double sim_initial_pressure_bar = 3.0;  // [hal.sim] initial_pressure_bar (physics)
  std::vector<std::string> sim_effects;   // [hal.sim] effects hidden in the hammerstein plant: "valve_lag=0.02"

  hal::ModbusIoConfig modbus_io;
  hal::ComediConfig comedi;
};

core::Result<ApplianceConfig> parse_appliance_config(const std::string& toml_text, const std::string& source_name);
core::Result<ApplianceConfig> read_appliance_config(const std::string& path);
const char* to_string(HalBackend backend);
// Whether the appliance serves Modbus at all: plain, or Modbus/TCP Security, or both.
inline bool serves_modbus(const ApplianceConfig& c) { return c.modbus.plain_enabled || c.modbus.secure.enabled; }
// True when any address may command motion: the Modbus server runs, writable, with no
// [modbus] write_clients. (HTTP commands always need the [web] token.) Said at start and in
// /api/status (any_address_may_command).
bool any_address_may_command(const ApplianceConfig& c);
// The start-up warning when any_address_may_command, else "".
std::string any_address_notice(const ApplianceConfig& c);

}  // namespace epa::config
