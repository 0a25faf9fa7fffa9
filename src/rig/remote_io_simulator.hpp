#pragma once
// A test rig, not part of the product's HAL: a stand-in for a remote analog I/O module with the plant behind it: a Modbus TCP server
// (libmodbus) whose registers follow a RemoteIoLayout, and a plant thread that steps a plant in
// real time: the paper's Hammerstein plant, or any plant::PlantSimulator (the physics model). `epa plant-server` runs it in its own process; the modbus-io
// tests run it in-process on a free port.
//
// Plant thread, every Ts (absolute deadlines, clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC):
// decode the valve register(s) (an undecodable value counts as 0 V, the centred valve), step the
// plant, encode its measured sensor volts into the sensor register(s). When it falls more than
// 10 periods behind (a suspended process) it starts a fresh schedule instead of catching up in a
// burst, and counts an overrun.
//
// Synchronised (sync_to_valve_writes): each step comes half a period after the master's last valve
// write (within half a period of the free schedule, so it locks after one write and the plant's
// rate stays bounded), as a module with synchronised I/O applies outputs and latches inputs at the
// master's sync point. Why: a plant that is itself a discrete model at the master's period (the
// paper's) adds, on a free clock, no delay or one whole sample depending on the two clocks' phase
// (a step between the master's read and its write applies the previous command), and the paper's
// FF-IDZ loop does not survive one sample (`epa simulate --delay 1`). Without writes it runs free.
//
// Server thread: select() over the listening socket and up to kMaxClients clients, waking at
// least every 50 ms so that stop() returns promptly; libmodbus' modbus_receive/modbus_reply do the
// protocol (modbus_reply also answers illegal addresses and functions with exceptions). Requests
// for the configured unit id or for 0xFF (Modbus TCP's "no unit id") are served; any other unit
// id gets exception 0x0B (gateway target device failed to respond) rather than silence, so that
// a misconfigured client gets a clear error at once instead of a timeout. A client that
// disconnects, sends garbage or stalls mid-frame for more than 100 ms is dropped; the server
// carries on. The register mapping is shared under a std::mutex: this is a test tool, not the
// real-time loop.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "hal/remote_io_layout.hpp"
#include "plant/hammerstein_plant.hpp"
#include "plant/plant_simulator.hpp"

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

// Faults a test injects into the module (epa plant-server --control-stdin): how it answers, and
// what its sensor reads. The defaults are a healthy module.
struct ModuleFaults {
  enum class Answers : std::uint8_t { kNormal, kSilent, kLate, kGarbage };
  enum class Sensor : std::uint8_t { kNormal, kNotANumber, kFixed, kFrozen };
  Answers answers = Answers::kNormal;
  int late_ms = 0;            // kLate: every answer this much late
  Sensor sensor = Sensor::kNormal;
  double sensor_v = 0.0;      // kFixed: what the sensor reads (e.g. out of range)
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
  std::uint64_t overruns() const; // times the plant thread gave up catching up (see above)
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

  // Stops both threads and closes every socket; idempotent. Returns within 50 ms + Ts, or 150 ms
  // + Ts while a client stalls mid-frame.
  void stop();

 private:
  struct Impl;
  explicit RemoteIoSimulator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace epa::rig
