#include "app/serve_command.hpp"

#include <spdlog/spdlog.h>

#include <optional>
#include <string>

#include "app/cli_checks.hpp"
#include "app/commissioning_identification.hpp"
#include "appliance/axis.hpp"
#include "appliance/control_setup.hpp"
#include "appliance/daq_factory.hpp"
#include "appliance/file_limit.hpp"
#include "appliance/interfaces.hpp"
#include "appliance/log_audit_sink.hpp"
#include "appliance/supervisor.hpp"
#include "core/format.hpp"
#include "core/log_throttle.hpp"
#include "core/version.hpp"
#include "hal/realtime.hpp"
#include "report/commission_report.hpp"
#include "web/recent_audit.hpp"

namespace epa::app {

void add_serve_command(CLI::App& app, ServeOptions& o) {
  auto* cmd = app.add_subcommand("serve", "Run the appliance: scan cycle, DAQ backend, run recorder");
  cmd->add_option("--config", o.config_path, "Configuration file (epa-config/1 TOML)")->capture_default_str();
  cmd->add_option("--hal", o.hal, "DAQ backend, overriding the configuration: sim, modbus-io, comedi");
  cmd->add_option("--modbus-io-port", o.modbus_io_port, "TCP port of the remote I/O module (modbus-io)")->check(CLI::Range(1, 65535));
  cmd->add_option("--modbus-port", o.modbus_port, "TCP port of the Modbus server, overriding [modbus] port (0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--web-port", o.web_port, "TCP port of the status page's HTTP server, overriding [web] port (0: any free port)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--mode", o.mode, "Mode at start-up: stop or run");
  cmd->add_option("--setpoint", o.setpoint_mm, "Setpoint at start-up, mm; in RUN the axis moves there (within the setpoint range)");
  cmd->add_option("--record-dir", o.record_dir, "Directory for recorded run files");
  cmd->add_option("--db", o.db_path, "The tuning store's database file, overriding [store] path");
  cmd->add_option("--duration", o.duration_s, "Stop by itself after this many seconds (0: run until SIGTERM)")->check(cli::kNonNegative);
}

namespace {

// Every thread of the appliance (scan cycle, store, Modbus, HTTP workers, recorder): deep enough
// for SQLite, JSON and the HTTP parser, small enough that the stacks locked with the loop's
// memory stay small.
constexpr std::size_t kThreadStackBytes = 512 * 1024;

// Lines of one repeatable kind (audit, move, refused) logged a minute: enough to follow a person
// at work, far below what a flooding client would make the log hold.
constexpr int kLinesPerMinute = 30;

// Applies the command-line overrides on top of the file, re-validating what they touch.
core::Status apply_overrides(const ServeOptions& o, config::ApplianceConfig& c) {
  if (!o.hal.empty()) {
    if (o.hal == "sim") c.backend = config::HalBackend::kSim;
    else if (o.hal == "modbus-io") c.backend = config::HalBackend::kModbusIo;
    else if (o.hal == "comedi") c.backend = config::HalBackend::kComedi;
    else return core::invalid_argument("--hal '" + o.hal + "' is not one of sim, modbus-io, comedi");
  }
  if (o.modbus_io_port) c.modbus_io.port = *o.modbus_io_port;
  if (o.modbus_port) c.modbus.port = *o.modbus_port;
  if (o.web_port) c.web.port = *o.web_port;
  if (!o.mode.empty()) {
    auto m = runtime::parse_mode(o.mode);
    if (!m) return core::invalid_argument("--mode '" + o.mode + "' is not a mode; at start-up: stop or run");  // the rest: validate()
    c.runtime.start_mode = *m;
  }
  if (o.setpoint_mm) c.runtime.start_setpoint_mm = *o.setpoint_mm, c.runtime.start_moves_to_setpoint = true;
  if (!o.record_dir.empty()) c.record_directory = o.record_dir;
  if (!o.db_path.empty()) c.store_path = o.db_path;
  if (auto s = runtime::validate(c.runtime); !s) return s;
  if (c.backend == config::HalBackend::kModbusIo) return hal::validate(c.modbus_io);
  return core::ok();
}

// The configuration file with the command line's overrides, and the register map it names when
// Modbus is enabled.
struct ServeConfig {
  config::ApplianceConfig appliance;
  std::optional<modbus::RegisterMap> register_map;
};

core::Result<ServeConfig> load_serve_config(const ServeOptions& o) {
  auto loaded = config::read_appliance_config(o.config_path);
  if (!loaded) return loaded.error();
  if (auto s = apply_overrides(o, *loaded); !s) return s.error();
  ServeConfig out{std::move(*loaded), std::nullopt};
  if (config::serves_modbus(out.appliance)) {
    auto map = modbus::RegisterMap::load(out.appliance.register_map_path);
    if (!map) return map.error();
    out.register_map = std::move(*map);
  }
  return out;
}

// What the store said at start, then the control law the axis starts with.
void log_control(const config::ApplianceConfig& c, const appliance::ControlSetup& control) {
  // In RUN without --setpoint the axis holds where it stands (enable_holds_position): the retained
  // or configured setpoint is not a move, and the log must not read as one.
  const bool holds = c.runtime.start_mode == runtime::Mode::kRun && c.runtime.enable_holds_position && !c.runtime.start_moves_to_setpoint;
  spdlog::info("controller {} (tuning set '{}': {}), model '{}', Ts {} s, start mode {}, {}",
               control::to_string(c.runtime.controller), control.store.set.name, control.store.set.source,
               control.store.model.name, control.store.model.model.Ts, runtime::to_string(c.runtime.start_mode),
               holds ? "holding the piston where it stands until a move is started"
                     : "setpoint " + core::format_number(c.runtime.start_setpoint_mm) + " mm");
}

// The last line, and the exit code: a timed run (a script, a test) learns from it that the axis
// ended in FAULT. A signal's stop exits 0 whatever the mode: systemd's stop is no failure of the
// unit.
int report_stop(appliance::StopCause cause, const runtime::Snapshot& last, const store::StoreWriter& store) {
  const auto saved = store.counters();
  spdlog::info("stopped: {}; {} of {} changes saved", appliance::describe_snapshot(last), saved.saved, saved.accepted);
  if (cause == appliance::StopCause::kDuration && last.mode == runtime::Mode::kFault) {
    spdlog::error("the run ended with the axis in FAULT ({}): exit {}", runtime::to_string(last.fault), kExitEndedInFault);
    return kExitEndedInFault;
  }
  return 0;
}

}  // namespace

int run_serve(const ServeOptions& o, std::ostream& err) {
  auto fail = [&err](const core::Error& e) { return err << "epa serve: " << e.message << "\n", 1; };
  hal::set_default_thread_stack(kThreadStackBytes);
  auto loaded = load_serve_config(o);
  if (!loaded) return fail(loaded.error());
  config::ApplianceConfig& c = loaded->appliance;
  auto limits = appliance::write_limits(c, o.config_path, loaded->register_map);
  if (!limits) return fail(limits.error());
  auto control = appliance::prepare_control(c, loaded->register_map, o.setpoint_mm.has_value());
  if (!control) return fail(control.error());
  for (const auto& line : control->store.notes) spdlog::info("{}", line);
  for (const auto& line : control->store.warnings) spdlog::warn("{}", line);
  auto daq = appliance::make_daq(c, control->plant_model.model);
  if (!daq) return fail(daq.error());
  spdlog::info("epa {} serve starting: config {}, DAQ {}", core::kVersion, o.config_path, (*daq)->describe());
  spdlog::info("{}", appliance::raise_file_limit());  // before any listener: connections are descriptors
  if (auto s = (*daq)->open(); !s) return spdlog::error("DAQ: {}", s.error().message), 1;
  log_control(c, *control);
  const sigset_t signals = appliance::block_stop_signals();  // before the first thread

  store::StoreWriter& store = *control->store.writer;
  core::LogThrottle log_throttle(kLinesPerMinute, 60.0);
  appliance::LogAuditSink log_audit(log_throttle, &store);
  web::RecentAudit audit(&log_audit);  // the last entries for the status page, the log, the store
  appliance::Axis axis(c, *control, std::move(*limits), std::move(*daq),
                       {store, audit, log_throttle, identify_for_commissioning(c.runtime.mm_per_volt), report::commission_report_html});
  store.start();
  axis.start_loop();  // before either interface opens: a client that gets an answer reads a live loop
  appliance::Interfaces interfaces;  // after the axis: they reach it until they are gone
  if (auto s = interfaces.start(c, loaded->register_map, axis, audit, store); !s) return spdlog::error("{}", s.error().message), 1;
  axis.start_recorder();

  const appliance::StopCause cause = appliance::supervise(c, o.duration_s, axis, signals, log_throttle);
  interfaces.stop();  // no more commands from either interface; then the loop's last cycle
  axis.stop();
  store.stop();  // every accepted change and run on disk (or logged as not saved)
  return report_stop(cause, axis.snapshot(), store);
}

}  // namespace epa::app
