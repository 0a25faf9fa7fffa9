#pragma once
// `epa plant-server --control-stdin`: fault injection for hardware-in-the-loop tests, one command
// per line on standard input, answered with one line on standard output:
//   answers normal | silent | garbage | late MS     how the module answers Modbus requests
//   sensor normal | nan | frozen | fixed VOLTS      what its sensor reads
//   physics KEY VALUE   a key of the physics plant's epa-pneumatic/1 file, from the next step on
//                       (e.g. "physics supply_pressure_bar 4.5"; a drifting axis); the Hammerstein
//                       plant refuses it
//   status      "valve V position MM steps_to_safe N watchdog ok|tripped" (N: plant steps from the
//               last sensor fault to the first 0 V valve command; -1: none yet)
// Anything else is answered "error: ..." naming what was wrong.
#include <atomic>
#include <ostream>
#include <string>
#include <thread>

#include "rig/remote_io_simulator.hpp"

namespace epa::app {

// Applies one command line to `sim`; returns the answer line.
std::string apply_module_command(const std::string& line, rig::RemoteIoSimulator& sim, rig::ModuleFaults& faults);

// Reads standard input on its own thread (polling, so stop() returns within 100 ms) until EOF or stop().
class ModuleFaultControl {
 public:
  ModuleFaultControl(rig::RemoteIoSimulator& sim, std::ostream& out);
  ~ModuleFaultControl() { stop(); }
  ModuleFaultControl(const ModuleFaultControl&) = delete;
  ModuleFaultControl& operator=(const ModuleFaultControl&) = delete;
  void stop();

 private:
  void run();
  rig::RemoteIoSimulator& sim_;
  std::ostream& out_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace epa::app
