#pragma once
// A test rig, not part of the product's HAL: a stand-in for a remote analog I/O module with the
// plant behind it, the paper's Hammerstein plant or any plant::PlantSimulator (the physics model).
// `epa plant-server` runs it in its own process; the modbus-io tests run it in-process on a free
// port. Four parts, each its own file:
//   module_registers  the module's registers, where a RemoteIoLayout puts the valve and the sensor
//   module_server     the Modbus TCP server answering from them (libmodbus), on its own thread
//   plant_loop        the plant stepped in real time between them, on its own thread, in sync with
//                     the master's valve writes if asked, with the module's comms watchdog
//   module_faults     what a test injects: how the module answers, what its sensor reads
// Here they are validated, started and stopped together.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "hal/remote_io_layout.hpp"
#include "plant/hammerstein_plant.hpp"
#include "plant/plant_simulator.hpp"
#include "rig/module_faults.hpp"

namespace epa::rig {

struct RemoteIoSimulatorConfig {
  std::string address = "127.0.0.1";  // IPv4 address to listen on; "0.0.0.0" for all
  int port = 1502;                    // 0: pick a free port (see RemoteIoSimulator::port())
  int unit_id = 1;                    // 0..247; others (except 0xFF) get exception 0x0B
  hal::RemoteIoLayout layout = hal::default_remote_io_layout();
  core::HammersteinModel model;       // its Ts is the real-time step period
  plant::PlantOptions plant;          // model and plant: for start(config) only
  int realtime_priority = 0;          // SCHED_FIFO for both threads, as a module's firmware answers in
                                      // bounded time; 0: normal priority (refusal is not an error)
  bool sync_to_valve_writes = false;  // step the plant half a period after each valve write, as a module
                                      // with synchronised I/O does; off: the plant's clock runs free
  int watchdog_ms = 0;                // a module's comms watchdog: no request for this long (after the
                                      // first) centres the valve until requests come back; 0: off
};

class RemoteIoSimulator {
 public:
  static constexpr int kMaxClients = 16;

  // Validates, binds and listens, then starts the server and plant threads. Errors name the
  // field, or the address:port and the system's reason when binding fails (e.g. in use).
  // start(config) serves the Hammerstein plant of config.model and config.plant; start(config,
  // plant) serves the given plant instead, stepped every plant->sample_period_s().
  static core::Result<std::unique_ptr<RemoteIoSimulator>> start(const RemoteIoSimulatorConfig& config);
  static core::Result<std::unique_ptr<RemoteIoSimulator>> start(const RemoteIoSimulatorConfig& config,
                                                                std::unique_ptr<plant::PlantSimulator> plant);
  ~RemoteIoSimulator();  // stop()
  RemoteIoSimulator(const RemoteIoSimulator&) = delete;
  RemoteIoSimulator& operator=(const RemoteIoSimulator&) = delete;

  int port() const;               // the bound port (the real one when configured as 0)
  double position_mm() const;     // true piston position, for tests and logs
  std::uint64_t steps() const;    // plant steps done
  std::uint64_t overruns() const; // times the plant thread gave up catching up (plant_loop.hpp)
  // When the step the plant thread waits for (or is doing) is due, on steady_clock (which is
  // CLOCK_MONOTONIC): tells a test a thread that woke late on a loaded machine from a wrong schedule.
  std::chrono::steady_clock::time_point next_step_due() const;
  std::uint64_t requests() const; // Modbus requests answered (including exceptions)
  int clients() const;            // clients connected now
  double valve_v() const;         // the valve command the plant got at its last step
  // Plant steps from the last sensor fault injected to the first step whose valve command was
  // 0 V (the appliance's safe command); -1 while none has been. For "safe within one cycle" checks.
  long steps_to_safe_valve() const;
  bool watchdog_tripped() const;  // the comms watchdog centres the valve now

  // Takes effect at the next request (answers) or plant step (sensor); thread-safe.
  void inject(const ModuleFaults& faults);
  // A physics plant's parameter, changed from the next plant step on (PlantLoop::change_physics);
  // thread-safe. A Hammerstein plant refuses, naming itself.
  core::Status change_physics(std::string_view key, double value);

  // Stops both threads and closes every socket; idempotent. Returns within 50 ms + Ts, or 150 ms
  // + Ts while a client stalls mid-frame.
  void stop();

 private:
  struct Impl;
  explicit RemoteIoSimulator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace epa::rig
