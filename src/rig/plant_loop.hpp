#pragma once
// The simulated module's plant, stepped in real time on its own thread. Every Ts (absolute
// deadlines, clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC): read the valve register (an
// undecodable value counts as 0 V, the centred valve), step the plant, write its measured sensor
// volts (or what an injected fault makes of them) into the sensor register. When it falls more
// than 10 periods behind (a suspended process) it starts a fresh schedule instead of catching up
// in a burst, and counts an overrun.
//
// Synchronised (sync_to_valve_writes): each step comes half a period after the master's last valve
// write (within half a period of the free schedule, so it locks after one write and the plant's
// rate stays bounded), as a module with synchronised I/O applies outputs and latches inputs at the
// master's sync point. Why: a plant that is itself a discrete model at the master's period (the
// paper's) adds, on a free clock, no delay or one whole sample depending on the two clocks' phase
// (a step between the master's read and its write applies the previous command), and the paper's
// FF-IDZ loop does not survive one sample (`epa simulate --delay 1`). Without writes it runs free.
//
// The module's comms watchdog (watchdog_ms > 0): no request for that long, after the first,
// centres the valve until requests come back.
//
// A physics plant's parameters can change while it runs (change_physics, from another thread):
// checked there, handed over, and taken by the plant thread before its next step, which never
// waits for the other thread (it tries the hand-over's lock and looks again a step later).
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string_view>

#include "hal/remote_io_layout.hpp"
#include "plant/plant_simulator.hpp"
#include "rig/module_faults.hpp"
#include "rig/module_registers.hpp"
#include "rig/module_server.hpp"

namespace epa::rig {

class PlantLoop {
 public:
  struct Setup {
    hal::AnalogPoint sensor;
    bool sync_to_valve_writes = false;
    int watchdog_ms = 0;
  };

  PlantLoop(const Setup& setup, std::unique_ptr<plant::PlantSimulator> plant, ModuleRegisters& registers,
            InjectedFaults& faults, const MasterActivity& activity);

  double sample_period_s() const { return plant_->sample_period_s(); }
  double measured_v() const { return plant_->measured_v(); }  // before the thread starts
  double position_mm() const { return position_mm_.load(); }   // the true piston position
  std::uint64_t steps() const { return steps_.load(); }
  std::uint64_t overruns() const { return overruns_.load(); }
  std::int64_t next_step_due_ns() const { return next_step_due_ns_.load(); }  // CLOCK_MONOTONIC
  double valve_v() const { return last_valve_v_.load(); }  // the command of the last step
  bool watchdog_tripped() const { return watchdog_tripped_.load(); }

  // The plant thread's loop, until `running` is false.
  void run(const std::atomic<bool>& running) noexcept;

  // Sets one epa-pneumatic/1 key (plant::set_pneumatic_key) from the next step on; thread-safe.
  // Errors: a plant without physical parameters, an unknown key, a value out of range or one the
  // plant's sub-steps cannot integrate; nothing changes then.
  core::Status change_physics(std::string_view key, double value);

 private:
  std::int64_t next_step_ns(std::int64_t last_step_ns, std::int64_t& step_before_ns) const noexcept;
  double valve_command(std::int64_t step_ns) noexcept;  // the register's, or 0 V while the watchdog trips
  void step(double valve_v) noexcept;
  void take_physics_change() noexcept;

  const Setup setup_;
  std::unique_ptr<plant::PlantSimulator> plant_;  // never null; the plant thread's alone once started
  const std::int64_t period_ns_;
  ModuleRegisters& registers_;
  InjectedFaults& faults_;
  const MasterActivity& activity_;
  std::atomic<double> position_mm_{0.0};
  std::atomic<std::uint64_t> steps_{0}, overruns_{0};
  std::atomic<double> last_valve_v_{0.0};
  std::atomic<std::int64_t> next_step_due_ns_{0};  // when the step the plant thread waits for is due
  std::atomic<bool> watchdog_tripped_{false};
  std::mutex physics_mutex_;                      // the hand-over below
  std::optional<plant::PneumaticParams> physics_;  // the parameters asked for last (none: not a physics plant)
  std::atomic<bool> physics_pending_{false};      // physics_ holds a change the plant has not taken
};

}  // namespace epa::rig
