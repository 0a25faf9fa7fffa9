#pragma once
// Faults a test injects into the simulated module (epa plant-server --control-stdin): how it
// answers Modbus requests and what its sensor reads, and how soon after a sensor fault the
// master made the valve safe. Each value is its own atomic, so neither the server nor the plant
// thread ever waits for the injector.
#include <atomic>
#include <cstdint>
#include <optional>

#include "hal/remote_io_layout.hpp"

namespace epa::rig {

// The defaults are a healthy module.
struct ModuleFaults {
  enum class Answers : std::uint8_t { kNormal, kSilent, kLate, kGarbage };
  enum class Sensor : std::uint8_t { kNormal, kNotANumber, kFixed, kFrozen };
  Answers answers = Answers::kNormal;
  int late_ms = 0;            // kLate: every answer this much late
  Sensor sensor = Sensor::kNormal;
  double sensor_v = 0.0;      // kFixed: what the sensor reads (e.g. out of range)
};

class InjectedFaults {
 public:
  // Takes effect at the next request (answers) or plant step (sensor). `steps_done`: the plant
  // steps so far, from which a new sensor fault counts the steps to a safe valve.
  void inject(const ModuleFaults& faults, std::uint64_t steps_done);

  ModuleFaults::Answers answers() const { return answers_.load(); }
  int late_ms() const { return late_ms_.load(); }
  // What the sensor register holds after a plant step whose reading is `measured_v`: that
  // reading, or what the injected fault makes of it; none: it keeps the last one (frozen).
  std::optional<hal::PointWords> sensor_words(const hal::AnalogPoint& sensor, double measured_v) const;

  // Plant step number `step` (from 0) ran with `valve_v`: the first 0 V command (the appliance's
  // safe one) after a sensor fault ends the count.
  void count_step(std::uint64_t step, double valve_v);
  long steps_to_safe_valve() const { return steps_to_safe_.load(); }  // -1: none yet

 private:
  std::atomic<ModuleFaults::Answers> answers_{ModuleFaults::Answers::kNormal};
  std::atomic<int> late_ms_{0};
  std::atomic<ModuleFaults::Sensor> sensor_{ModuleFaults::Sensor::kNormal};
  std::atomic<double> fixed_sensor_v_{0.0};
  std::atomic<std::int64_t> sensor_fault_step_{-1};  // plant step at which a sensor fault was injected
  std::atomic<long> steps_to_safe_{-1};
};

}  // namespace epa::rig
