#include "appliance/axis.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <string>
#include <vector>

#include "appliance/byte_sizes.hpp"
#include "appliance/commissioning_axis.hpp"
#include "appliance/run_history.hpp"
#include "appliance/throttled_log.hpp"
#include "hal/realtime.hpp"
#include "store/set_activation.hpp"
#include "store/store_file.hpp"

namespace epa::appliance {

namespace {

// What this appliance can run, from the gate's limits: a commissioning spec beyond them is refused
// before the axis is touched.
commission::ApplianceBounds commissioning_bounds(const points::WriteLimits& limits) {
  return {.setpoint_min_mm = limits.range(points::PointId::kSetpoint).min.value,
          .setpoint_max_mm = limits.range(points::PointId::kSetpoint).max.value,
          .excitation_max_s = limits.range(points::PointId::kExciteDuration).max.value,
          .excitation_max_source = limits.range(points::PointId::kExciteDuration).max.source,
          .amplitude_max_v = limits.range(points::PointId::kExciteAmplitudeMax).max.value};
}

runtime::RecorderConfig recorder_config(const config::ApplianceConfig& c) {
  return {.directory = c.record_directory,
          .per_move = c.record_per_move,
          .Ts = c.runtime.period_s,
          .source = std::string("appliance/") + to_string(c.backend),
          .quota_bytes = mib_to_bytes(c.record_quota_mb),
          .move_files_per_minute = c.record_move_files_per_minute,
          .min_free_bytes = mib_to_bytes(c.store_min_free_mb)};
}

// The running set's model, as the health monitor follows it (read from the store's file: the
// monitor's thread has no other way in).
core::Result<MonitoredModel> monitored_model(const std::string& store_path, std::int64_t set_id) {
  auto db = store::open_existing_store(store_path);
  if (!db) return db.error();
  auto loaded = store::find_set_with_model(*db, std::to_string(set_id));
  if (!loaded) return loaded.error();
  return MonitoredModel{loaded->set.name, loaded->model.stick_slip, loaded->model.model.Ts};
}

}  // namespace

Axis::Axis(const config::ApplianceConfig& config, const ControlSetup& control, points::WriteLimits limits,
           std::unique_ptr<hal::Daq> daq, AxisServices services)
    : config_(config),
      services_(std::move(services)),
      daq_(std::move(daq)),
      channels_(runtime::record_capacity_samples(config.runtime)),
      loop_(config.runtime, control.tuning, *daq_, clock_, channels_),
      gate_(std::move(limits), config.runtime, control.tuning_base, channels_, &services_.audit, control.store.records) {
  channels_.fault_history.load(control.store.faults, control.store.fault_count);
  // Every reader of the history looks at the ring first (FaultHistory::set_intake).
  channels_.fault_history.set_intake([this] { take_fault_events(); });
  // Its axis is this loop, through the gate, the recorder and the store. The gate reaches it until
  // stop(), which detaches it before the loop takes its last commands.
  auto make_axis = [this](const std::string& source) -> std::unique_ptr<commission::Axis> {
    return std::make_unique<CommissioningAxis>(config_.runtime, channels_, gate_, services_.store, config_.store_path, recorded_,
                                               points::Requester{source, true, "", /*tuning_unlocked=*/true});
  };
  commissioning_ = std::make_unique<CommissioningService>(
      make_axis, services_.identify, services_.render_report, commissioning_bounds(gate_.limits()),
      [](const std::string& line) { spdlog::info("{}", line); }, &services_.audit);
  gate_.attach_commission(commissioning_.get());
  health_ = std::make_unique<HealthMonitor>(
      config_.health, [this] { return services_.store.running_set_id(); },
      [this](std::int64_t set_id) { return monitored_model(config_.store_path, set_id); }, &services_.audit,
      [](bool warning, const std::string& line) { warning ? spdlog::warn("{}", line) : spdlog::info("{}", line); },
      [this](const std::string& text) { note_health_warning(text); });
  gate_.attach_health(health_.get());
}

Axis::~Axis() {
  stop_loop();
  daq_->close();
}

void Axis::start_loop() {
  loop_thread_ = std::thread([this] {
    for (const auto& warning : hal::request_realtime(config_.realtime)) spdlog::warn("{}", warning);
    loop_.run(loop_stop_);
  });
  for (int i = 0; i < 200 && channels_.snapshot.read().cycle == 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
}

void Axis::start_recorder() {
  recorder_.emplace(
      recorder_config(config_), channels_,
      [this](const std::string& line) { log_throttled(services_.log_throttle, "recorder", spdlog::level::info, line); },
      [this](const std::string& path, const core::Run& run) {
        services_.store.record_run(to_run_record(path, run));
        recorded_.put(path, run);
      });
  // The monitor judges a move from the rest it started at, which its file does not hold.
  recorder_->on_move_with_rest([this](const core::Run& move) { health_->add_run(move, channels_.snapshot.read().axis.hunting); });
  recorder_->start();
}

void Axis::stop_loop() {
  gate_.attach_commission(nullptr);
  commissioning_.reset();  // a commissioning run under way is aborted: valve safe, the previous set back
  loop_stop_ = true;
  if (loop_thread_.joinable()) loop_thread_.join();  // the loop's last act: valve to its safe command
}

void Axis::stop() {
  stop_loop();
  take_fault_events();                 // latched since the supervisor's last look
  if (recorder_) recorder_->stop();    // writes what is pending
  gate_.attach_health(nullptr);
  health_.reset();                     // moves still queued are not judged
}

// A model-health warning's start, change or end, in the fault history beside the faults (its code
// says it is none): where the loop stood when the verdict changed, the valve and sensor unknown.
void Axis::note_health_warning(const std::string& text) {
  const runtime::Snapshot snap = channels_.snapshot.read();
  runtime::FaultRecord f;
  f.time_ms = core::unix_time_ms();
  f.code = runtime::FaultCode::kModelHealth;
  f.mode = snap.mode;
  f.position_mm = snap.position_mm;
  f.setpoint_mm = snap.setpoint_mm;
  f.name = std::string(runtime::to_string(f.code));
  f.text = text;
  keep_in_history(std::move(f));
}

void Axis::keep_in_history(runtime::FaultRecord record) {
  services_.store.record_fault(record);
  channels_.fault_history.add(std::move(record));
}

// From the loop's events, never from the snapshot (a reset in the next cycle has cleared the
// snapshot's fault). Stamped with the wall clock now, less how long ago the loop latched it.
// Called by the supervisor on its tick and by every reader of the history before it reads: the
// ring has one consumer at a time, whichever looks first.
void Axis::take_fault_events() {
  std::lock_guard lock(fault_intake_);
  std::vector<runtime::FaultEvent> events;
  runtime::FaultEvent e;
  while (channels_.fault_events.try_pop(e)) events.push_back(e);
  if (events.empty()) return;
  const double loop_now_s = channels_.snapshot.read().time_s;  // read after the events: not older than they are
  const std::int64_t now_ms = core::unix_time_ms();
  for (const runtime::FaultEvent& event : events) {
    runtime::FaultRecord f = runtime::fault_record(event, runtime::fault_time_ms(event, loop_now_s, now_ms));
    spdlog::error("FAULT {}: {} (in {}, position {:.2f} mm, setpoint {:.2f} mm, valve {:.3f} V, sensor {:.3f} V)", f.name, f.text,
                  runtime::to_string(f.mode), f.position_mm, f.setpoint_mm, f.valve_v, f.sensor_v);
    keep_in_history(std::move(f));
  }
}

}  // namespace epa::appliance
