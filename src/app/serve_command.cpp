#include "app/serve_command.hpp"

#include <spdlog/spdlog.h>
#include <systemd/sd-daemon.h>

#include <atomic>
#include <csignal>
#include <ctime>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "app/cli_checks.hpp"
#include "app/daq_factory.hpp"
#include "app/file_limit.hpp"
#include "app/appliance_axis.hpp"
#include "app/commission_identify.hpp"
#include "app/commission_service.hpp"
#include "app/log_audit_sink.hpp"
#include "app/run_history.hpp"
#include "app/store_setup.hpp"
#include "app/tuning_source.hpp"
#include "core/audit.hpp"
#include "core/format.hpp"
#include "core/log_throttle.hpp"
#include "core/version.hpp"
#include "hal/realtime.hpp"
#include "runtime/clock.hpp"
#include "runtime/recorder.hpp"
#include "runtime/scan_cycle.hpp"
#include "web/recent_audit.hpp"
#include "web/web_server.hpp"

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

std::uint64_t mib(double megabytes) { return static_cast<std::uint64_t>(megabytes * 1024 * 1024); }

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

std::string describe_snapshot(const runtime::Snapshot& s) {
  char buf[256];
  std::snprintf(buf, sizeof buf, "mode %s, %s, setpoint %.2f mm, position %.2f mm, valve %.3f V, moves %llu, loop p99 wake-up %.0f us, overruns %llu",
                std::string(runtime::to_string(s.mode)).c_str(), std::string(control::to_string(s.controller)).c_str(),
                s.setpoint_mm, s.position_mm, s.valve_v, static_cast<unsigned long long>(s.moves), s.loop.wake_p99_us,
                static_cast<unsigned long long>(s.loop.overruns));
  return buf;
}

// Everything the control law needs: the active tuning set from the store (seeded from the
// configuration's model and design files on first start), and the configuration's model for the
// sim backend's plant.
struct ControlSetup {
  core::ModelFile plant_model;            // the configuration's model: what the sim backend simulates
  StoreStartup store;                     // the active tuning set, its model, the store thread
  control::ControllerConfig tuning_base;  // the running tuning, handed to its owner, the write gate
  runtime::Tuning tuning;
};

// The points whose accepted values the store keeps: the register map's persisted column (without
// Modbus, the setpoint), and always the position-record table, whichever interface edits it.
std::set<points::PointId> persisted_points(const std::optional<modbus::RegisterMap>& map) {
  std::set<points::PointId> out;
  if (!map) out.insert(points::PointId::kSetpoint);
  for (const auto& e : map ? map->entries() : std::vector<modbus::RegisterEntry>{})
    if (e.persisted) out.insert(e.point->id);
  for (std::size_t k = 0; k < 4 * points::kPositionRecords; ++k) out.insert(points::indexed_id(points::PointId::kRecordTarget0, k));
  return out;
}

// The one set of write limits: the catalog's, narrowed by the configuration and the register map;
// the start-up setpoint (configuration or --setpoint) must lie within them too.
core::Result<points::WriteLimits> write_limits(const config::ApplianceConfig& c, const std::string& config_path,
                                               const std::optional<modbus::RegisterMap>& map) {
  auto limits = points::WriteLimits::from_config(c.runtime, config_path);
  if (!limits) return limits.error();
  if (map)
    if (auto s = modbus::narrow_limits(*map, *limits); !s) return s.error();
  if (auto why = limits->check(points::PointId::kSetpoint, c.runtime.start_setpoint_mm); !why.empty())
    return core::invalid_argument("start-up setpoint: " + why);
  return limits;
}

core::Result<ControlSetup> prepare_control(config::ApplianceConfig& c, const std::optional<modbus::RegisterMap>& map, bool setpoint_given) {
  auto plant_model = load_model(c.model_path);
  if (!plant_model) return plant_model.error();
  // The paper does not print its Ts (NOTES.md), so its model takes the loop's period; an
  // identified model is only valid at the Ts it was identified at.
  if (c.model_path.empty()) plant_model->model.Ts = c.runtime.period_s;
  auto polynomials = load_controller_polynomials(c.design_path);
  if (!polynomials) return polynomials.error();
  const bool paper = c.model_path.empty() && c.design_path.empty();
  const auto seed = make_seed(paper ? "paper" : "initial", *plant_model, *polynomials, c.runtime.controller, c.lc_mm, c.valve_limit_v);
  auto store = open_tuning_store(c.store_path, seed, persisted_points(map), c.runtime.period_s);
  if (!store) return store.error();

  const core::HammersteinModel& model = store->model.model;  // its Ts is the loop's (load_active_tuning)
  c.runtime.mm_per_volt = model.mm_per_volt;
  c.runtime.controller = store->set.controller;
  c.runtime.start_fault = store->start_fault;
  if (store->retained_setpoint_mm && !setpoint_given) {
    const double r = *store->retained_setpoint_mm;
    if (r >= c.runtime.setpoint_min_mm && r <= c.runtime.setpoint_max_mm) c.runtime.start_setpoint_mm = r;
    else store->warnings.push_back("store: retained setpoint " + core::format_number(r) + " mm is outside the configured limits: not used");
  }
  const control::ControllerConfig base =
      runtime::with_travel_range(store::controller_config(store->set, model, c.runtime.safe_valve_v), c.runtime);
  auto tuning = runtime::make_tuning(base);
  if (!tuning) return tuning.error();  // cannot happen: load_active_tuning validated the set
  return ControlSetup{std::move(*plant_model), std::move(*store), base, *tuning};
}

// `status_page_url`: the status page's address (FC43's VendorUrl), "" with none.
core::Result<std::unique_ptr<modbus::ModbusServer>> start_modbus(const config::ApplianceConfig& c, const modbus::RegisterMap& map,
                                                                 points::WriteGate& gate, runtime::LoopChannels& channels,
                                                                 std::string status_page_url) {
  modbus::ServerConfig mc = c.modbus;
  mc.status_page_url = std::move(status_page_url);
  auto server = modbus::ModbusServer::start(mc, map, gate, channels, [](const std::string& line) { spdlog::info("{}", line); });
  if (!server) return server.error();
  const auto& p = c.modbus.policy;
  std::string aliases;
  for (const int id : c.modbus.alias_unit_ids) aliases += (aliases.empty() ? ", also " : " and ") + std::to_string(id);
  spdlog::info("modbus: listening on {} (unit {}{}, map {}, {} points, {})", (*server)->bound_address(),
               c.modbus.unit_id, aliases, c.register_map_path, map.entries().size(),
               p.read_only ? "read-only" : p.unlock_key ? "tuning locked until unlocked" : "tuning locked (no unlock key)");
  if (const std::string notice = config::any_address_notice(c); !notice.empty()) spdlog::warn("{}", notice);
  return server;
}

// `modbus`: the Modbus server once it has started (after the web server: its identity names the
// status page's port), null while it has not or without one.
core::Result<std::unique_ptr<web::WebServer>> start_web(const config::ApplianceConfig& c, runtime::LoopChannels& channels,
                                                        points::WriteGate& gate, web::RecentAudit& audit,
                                                        const std::atomic<const modbus::ModbusServer*>& modbus,
                                                        const store::StoreWriter& store, web::CommissionPort* commission) {
  auto modbus_stats = [&modbus, any_address = config::any_address_may_command(c)] {
    const modbus::ModbusServer* mb = modbus.load();
    return mb ? web::ModbusStats{true, mb->clients(), mb->requests(), mb->exceptions(), any_address} : web::ModbusStats{};
  };
  auto store_stats = [&store] {
    const auto counters = store.counters();
    const auto health = store.health();
    return web::StoreStats{true, health.ok, counters.accepted, counters.saved, health.last_error, store.running_set().name,
                           counters.disk_low};
  };
  web::WebConfig web_config = c.web;
  web_config.log = [](const std::string& line) { spdlog::warn("{}", line); };
  auto server = web::WebServer::start(web_config, channels, &gate, &audit, modbus_stats, store_stats, commission);
  if (!server) return server.error();
  spdlog::info("web: listening on {} (static files {}, commands {})", (*server)->bound_address(), c.web.static_dir,
               c.web.token.empty() ? "disabled: no token configured" : "enabled with the token");
  return server;
}

// A line of a kind a client can repeat at request speed (moves, refusals, audit entries), through
// the throttle: the held-back ones are counted in the next summary.
void log_throttled(core::LogThrottle& throttle, const char* kind, spdlog::level::level_enum level, const std::string& line) {
  std::string summary;
  const bool admitted = throttle.admit(kind, summary);
  if (!summary.empty()) spdlog::log(level, "{}", summary);
  if (admitted) spdlog::log(level, "{}", line);
}

// What the operator should read in the log between two snapshots: mode changes, moves. (Faults
// come from the loop's events: take_fault_events.)
void log_changes(const runtime::Snapshot& previous, const runtime::Snapshot& s, core::LogThrottle& throttle) {
  if (s.mode != previous.mode) spdlog::info("mode {} -> {}", runtime::to_string(previous.mode), runtime::to_string(s.mode));
  if (s.fault_events_dropped != previous.fault_events_dropped)
    spdlog::warn("{} fault(s) latched with the fault event ring full: counted in faults, missing from the fault history",
                 s.fault_events_dropped - previous.fault_events_dropped);
  if (s.moves != previous.moves)
    log_throttled(throttle, "move", spdlog::level::info,
                  fmt::format("move {} {:.1f} -> {:.1f} mm ({}, {}): rise {:.3f} s, settling {:.3f} s, e_ss {:.2f} mm, overshoot {:.1f} %",
                              s.last_move.number, s.last_move.from_mm, s.last_move.to_mm, control::to_string(s.last_move.controller),
                              core::to_string(static_cast<core::MoveEnd>(s.last_move.end)), s.last_move.rise_s,
                              s.last_move.settling_s, s.last_move.ess_mm, s.last_move.overshoot_pct));
}

// Each fault the loop latched, from its event, never from the snapshot (a reset in the next cycle
// has cleared the snapshot's fault): logged with its cause, added to the history the interfaces
// read, and handed to the store thread. Stamped with the wall clock now, less how long ago the
// loop latched it. Called by the supervisor on its tick and by every reader of the history before
// it reads (FaultHistory::set_intake): the ring has one consumer at a time, whichever looks first.
void take_fault_events(runtime::LoopChannels& channels, store::StoreWriter& store_writer) {
  static std::mutex one_consumer;
  std::lock_guard lock(one_consumer);
  std::vector<runtime::FaultEvent> events;
  runtime::FaultEvent e;
  while (channels.fault_events.try_pop(e)) events.push_back(e);
  if (events.empty()) return;
  const double loop_now_s = channels.snapshot.read().time_s;  // read after the events: not older than they are
  const std::int64_t now_ms = core::unix_time_ms();
  for (const runtime::FaultEvent& event : events) {
    runtime::FaultRecord f = runtime::fault_record(event, runtime::fault_time_ms(event, loop_now_s, now_ms));
    spdlog::error("FAULT {}: {} (in {}, position {:.2f} mm, setpoint {:.2f} mm, valve {:.3f} V, sensor {:.3f} V)", f.name, f.text,
                  runtime::to_string(f.mode), f.position_mm, f.setpoint_mm, f.valve_v, f.sensor_v);
    store_writer.record_fault(f);
    channels.fault_history.add(std::move(f));
  }
}

// The main thread while the appliance runs: waits for SIGTERM/SIGINT (or the duration), logs
// events and a periodic status, keeps the fault history, has the gate log and audit the commands
// the loop refused after acceptance, and pings the systemd watchdog only while the loop advances,
// so a stuck loop gets the unit restarted.
enum class StopCause { kSignal, kDuration };
StopCause supervise(const config::ApplianceConfig& c, double duration_s, runtime::LoopChannels& channels, points::WriteGate& gate,
                    store::StoreWriter& store_writer, const sigset_t& signals, core::LogThrottle& throttle) {
  std::uint64_t watchdog_usec = 0;
  const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0;
  const auto started = std::chrono::steady_clock::now();
  auto last_status = started, last_ping = started;
  runtime::Snapshot previous = channels.snapshot.read();
  std::uint64_t cycle_at_last_ping = previous.cycle;
  const timespec tick{0, 50'000'000};  // 50 ms: events are logged within that
  for (;;) {
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig == SIGTERM || sig == SIGINT) {
      spdlog::info("signal {}: shutting down", sig == SIGTERM ? "SIGTERM" : "SIGINT");
      return StopCause::kSignal;
    }
    const auto now = std::chrono::steady_clock::now();
    const runtime::Snapshot s = channels.snapshot.read();
    take_fault_events(channels, store_writer);
    log_changes(previous, s, throttle);
    gate.take_refusals([&throttle](const std::string& line) { log_throttled(throttle, "refused", spdlog::level::warn, line); });
    for (const std::string& summary : throttle.due_summaries()) spdlog::info("{}", summary);
    previous = s;
    if (c.status_interval_s > 0 && now - last_status >= std::chrono::duration<double>(c.status_interval_s)) {
      spdlog::info("status: {}", describe_snapshot(s));
      last_status = now;
    }
    if (watchdog && now - last_ping >= std::chrono::microseconds(watchdog_usec / 2)) {
      if (s.cycle != cycle_at_last_ping) sd_notify(0, "WATCHDOG=1");
      cycle_at_last_ping = s.cycle;
      last_ping = now;
    }
    if (duration_s > 0 && now - started >= std::chrono::duration<double>(duration_s)) {
      spdlog::info("duration of {} s reached: shutting down", duration_s);
      return StopCause::kDuration;
    }
  }
}

// The scan cycle's thread, stopped and joined on every way out of run_serve.
struct LoopThread {
  std::atomic<bool> stop{false};
  std::thread thread;
  void join() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  ~LoopThread() { join(); }
};

// Closes the DAQ on every way out of run_serve.
struct DaqCloser {
  hal::Daq& daq;
  ~DaqCloser() { daq.close(); }
};

}  // namespace

int run_serve(const ServeOptions& o, std::ostream& err) {
  auto fail = [&err](const core::Error& e) { return err << "epa serve: " << e.message << "\n", 1; };
  hal::set_default_thread_stack(kThreadStackBytes);
  auto loaded = config::read_appliance_config(o.config_path);
  if (!loaded) return fail(loaded.error());
  if (auto s = apply_overrides(o, *loaded); !s) return fail(s.error());
  config::ApplianceConfig& c = *loaded;
  std::optional<modbus::RegisterMap> register_map;
  if (c.modbus_enabled) {
    auto map = modbus::RegisterMap::load(c.register_map_path);
    if (!map) return fail(map.error());
    register_map = std::move(*map);
  }
  auto limits = write_limits(c, o.config_path, register_map);
  if (!limits) return fail(limits.error());
  auto control = prepare_control(c, register_map, o.setpoint_mm.has_value());
  if (!control) return fail(control.error());
  for (const auto& line : control->store.notes) spdlog::info("{}", line);
  for (const auto& line : control->store.warnings) spdlog::warn("{}", line);
  store::StoreWriter& store_writer = *control->store.writer;
  store_writer.set_limits({.audit_max_rows = c.audit_max_rows, .min_free_bytes = mib(c.store_min_free_mb)});
  auto daq = make_daq(c, control->plant_model.model);
  if (!daq) return fail(daq.error());
  spdlog::info("epa {} serve starting: config {}, DAQ {}", core::kVersion, o.config_path, (*daq)->describe());
  spdlog::info("{}", raise_file_limit());  // before any listener: connections are descriptors
  if (auto s = (*daq)->open(); !s) {
    spdlog::error("DAQ: {}", s.error().message);
    return 1;
  }
  const DaqCloser closer{**daq};
  // In RUN without --setpoint the axis holds where it stands (enable_holds_position): the retained
  // or configured setpoint is not a move, and the log must not read as one.
  const bool holds = c.runtime.start_mode == runtime::Mode::kRun && c.runtime.enable_holds_position && !c.runtime.start_moves_to_setpoint;
  spdlog::info("controller {} (tuning set '{}': {}), model '{}', Ts {} s, start mode {}, {}",
               control::to_string(c.runtime.controller), control->store.set.name, control->store.set.source,
               control->store.model.name, control->store.model.model.Ts, runtime::to_string(c.runtime.start_mode),
               holds ? "holding the piston where it stands until a move is started"
                     : "setpoint " + core::format_number(c.runtime.start_setpoint_mm) + " mm");

  // SIGTERM/SIGINT are taken synchronously by this thread; the threads below inherit the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  runtime::LoopChannels channels(runtime::record_capacity_samples(c.runtime));
  channels.fault_history.load(control->store.faults, control->store.fault_count);
  channels.fault_history.set_intake([&channels, &store_writer] { take_fault_events(channels, store_writer); });
  runtime::MonotonicClock clock;
  runtime::ScanCycle loop(c.runtime, control->tuning, **daq, clock, channels);
  store_writer.start();
  // The loop runs before either interface opens, so a client that gets an answer reads a live
  // loop (its first cycle is waited for, at most 1 s).
  LoopThread loop_thread;
  loop_thread.thread = std::thread([&] {
    for (const auto& warning : hal::request_realtime(c.realtime)) spdlog::warn("{}", warning);
    loop.run(loop_thread.stop);
  });
  for (int i = 0; i < 200 && channels.snapshot.read().cycle == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  core::LogThrottle log_throttle(kLinesPerMinute, 60.0);
  LogAuditSink log_audit(log_throttle, &store_writer);
  web::RecentAudit audit(&log_audit);  // the last entries for the status page, the log, the store
  points::WriteGate gate(std::move(*limits), c.runtime, control->tuning_base, channels, &audit, control->store.records);  // every interface's writes
  // Commissioning (issue 19): its axis is this loop, through the gate, the recorder and the store.
  // Declared before the interfaces, so it outlives them on every way out (they reach it through
  // the gate), and after the loop, which takes its last commands when it is aborted.
  RecordedRuns recorded;
  auto make_axis = [&](const std::string& source) -> std::unique_ptr<commission::Axis> {
    return std::make_unique<ApplianceAxis>(c.runtime, channels, gate, store_writer, c.store_path, recorded,
                                           points::Requester{source, true, "", /*tuning_unlocked=*/true});
  };
  const auto& limits_now = gate.limits();
  const commission::ApplianceBounds bounds{
      .setpoint_min_mm = limits_now.range(points::PointId::kSetpoint).min.value,
      .setpoint_max_mm = limits_now.range(points::PointId::kSetpoint).max.value,
      .excitation_max_s = limits_now.range(points::PointId::kExciteDuration).max.value,
      .excitation_max_source = limits_now.range(points::PointId::kExciteDuration).max.source,
      .amplitude_max_v = limits_now.range(points::PointId::kExciteAmplitudeMax).max.value};
  auto commissioning = std::make_unique<CommissionService>(make_axis, identify_for_commissioning(c.runtime.mm_per_volt), bounds,
                                                           [](const std::string& line) { spdlog::info("{}", line); }, &audit);
  gate.attach_commission(commissioning.get());
  // The web server starts first, so the Modbus identity names the port it bound (VendorUrl; with
  // `port = 0` only the bind knows it), and stops first (declared after the Modbus server): its
  // status reads the Modbus server's counters through `modbus_for_web`, set once that runs.
  std::atomic<const modbus::ModbusServer*> modbus_for_web{nullptr};
  std::unique_ptr<modbus::ModbusServer> modbus_server;
  std::unique_ptr<web::WebServer> web_server;
  if (c.web_enabled) {
    auto server = start_web(c, channels, gate, audit, modbus_for_web, store_writer, commissioning.get());
    if (!server) return spdlog::error("{}", server.error().message), 1;
    web_server = std::move(*server);
  }
  if (register_map) {
    auto server = start_modbus(c, *register_map, gate, channels,
                               web_server ? modbus::status_page_url(web_server->port()) : std::string());
    if (!server) return spdlog::error("{}", server.error().message), 1;
    modbus_server = std::move(*server);
    modbus_for_web = modbus_server.get();
  }
  runtime::Recorder recorder({.directory = c.record_directory, .per_move = c.record_per_move, .Ts = c.runtime.period_s,
                              .source = std::string("appliance/") + to_string(c.backend),
                              .quota_bytes = mib(c.record_quota_mb),
                              .move_files_per_minute = c.record_move_files_per_minute,
                              .min_free_bytes = mib(c.store_min_free_mb)},
                             channels,
                             [&log_throttle](const std::string& line) { log_throttled(log_throttle, "recorder", spdlog::level::info, line); },
                             [&store_writer, &recorded](const std::string& path, const core::Run& run) {
                               store_writer.record_run(to_run_record(path, run));
                               recorded.put(path, run);
                             });
  recorder.start();

  sd_notify(0, "READY=1");
  spdlog::info("running");
  const StopCause cause = supervise(c, o.duration_s, channels, gate, store_writer, signals, log_throttle);

  sd_notify(0, "STOPPING=1");
  if (web_server) web_server->stop();        // no more commands from either interface;
  if (modbus_server) modbus_server->stop();  // then the loop's last cycle
  gate.attach_commission(nullptr);
  commissioning.reset();  // a commissioning run under way is aborted: valve safe, the previous set back
  loop_thread.join();  // the loop's last act: valve to its safe command
  take_fault_events(channels, store_writer);  // latched since the supervisor's last look
  recorder.stop();     // writes what is pending; the DAQ closes on the way out
  store_writer.stop(); // every accepted change and run on disk (or logged as not saved)
  const auto saved = store_writer.counters();
  const runtime::Snapshot last = channels.snapshot.read();
  spdlog::info("stopped: {}; {} of {} changes saved", describe_snapshot(last), saved.saved, saved.accepted);
  // A timed run (a script, a test) learns from the exit code that the axis ended it in FAULT. A
  // signal's stop exits 0 whatever the mode: systemd's stop is no failure of the unit.
  if (cause == StopCause::kDuration && last.mode == runtime::Mode::kFault) {
    spdlog::error("the run ended with the axis in FAULT ({}): exit {}", runtime::to_string(last.fault), kExitEndedInFault);
    return kExitEndedInFault;
  }
  return 0;
}

}  // namespace epa::app
