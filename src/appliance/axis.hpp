#pragma once
// One axis of the appliance: its scan cycle on its own (real-time if allowed) thread, the channels
// every other thread meets it through, the write gate every interface writes through, the run
// recorder, the commissioning service, the model-health monitor that judges the recorded moves,
// and the intake that moves the faults it latches into the history and the store. Built from the parsed configuration and the store's tuning; a second
// axis is a second instance with its own DAQ.
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "appliance/commissioning_service.hpp"
#include "appliance/control_setup.hpp"
#include "appliance/health_monitor.hpp"
#include "appliance/recorded_runs.hpp"
#include "config/appliance_config.hpp"
#include "core/audit.hpp"
#include "core/log_throttle.hpp"
#include "hal/daq.hpp"
#include "points/write_gate.hpp"
#include "runtime/clock.hpp"
#include "runtime/loop_channels.hpp"
#include "runtime/recorder.hpp"
#include "runtime/scan_cycle.hpp"
#include "store/store_writer.hpp"

namespace epa::appliance {

// What an axis shares with the rest of the appliance, and the two steps of commissioning that
// belong to other libraries (the identification pipeline, the report's charts).
struct AxisServices {
  store::StoreWriter& store;         // keeps accepted changes, runs and faults
  core::AuditSink& audit;            // where the gate and the commissioning audit, with who asked
  core::LogThrottle& log_throttle;   // the recorder's lines, a bounded number a minute
  commission::Identify identify;
  CommissioningService::RenderReport render_report;
};

class Axis {
 public:
  // `config` outlives the axis; `daq` is open, and closed when the axis goes.
  Axis(const config::ApplianceConfig& config, const ControlSetup& control, points::WriteLimits limits,
       std::unique_ptr<hal::Daq> daq, AxisServices services);
  ~Axis();  // aborts a commissioning run, stops the loop (valve safe), closes the DAQ
  Axis(const Axis&) = delete;
  Axis& operator=(const Axis&) = delete;

  // Runs the scan cycle on its thread and waits (at most 1 s) for its first cycle, so a client
  // that gets an answer reads a live loop.
  void start_loop();
  // Starts writing run files. After the interfaces: the first file may be a request of theirs.
  void start_recorder();
  // After the interfaces have stopped: the commissioning run aborted, the loop's last cycle
  // (valve to its safe command), the faults latched since the last look, the pending run files.
  void stop();

  // Each fault the loop latched, logged, added to the history and handed to the store.
  void take_fault_events();

  runtime::LoopChannels& channels() { return channels_; }
  points::WriteGate& gate() { return gate_; }
  CommissioningService& commissioning() { return *commissioning_; }
  runtime::Snapshot snapshot() const { return channels_.snapshot.read(); }

 private:
  void stop_loop();
  // A model-health warning's start, change or end (HealthMonitor's history note), in the history.
  void note_health_warning(const std::string& text);
  // An entry of the history, handed to the store and added to what the interfaces read.
  void keep_in_history(runtime::FaultRecord record);

  const config::ApplianceConfig& config_;
  AxisServices services_;
  std::unique_ptr<hal::Daq> daq_;
  runtime::LoopChannels channels_;
  runtime::MonotonicClock clock_;
  runtime::ScanCycle loop_;
  std::atomic<bool> loop_stop_{false};
  std::thread loop_thread_;
  std::mutex fault_intake_;  // the fault ring has one consumer at a time
  points::WriteGate gate_;
  RecordedRuns recorded_;
  std::unique_ptr<CommissioningService> commissioning_;
  std::unique_ptr<HealthMonitor> health_;
  std::optional<runtime::Recorder> recorder_;
};

}  // namespace epa::appliance
