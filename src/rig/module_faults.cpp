#include "rig/module_faults.hpp"

#include <limits>

#include "core/word_order.hpp"

namespace epa::rig {

void InjectedFaults::inject(const ModuleFaults& f, std::uint64_t steps_done) {
  late_ms_.store(f.late_ms);
  answers_.store(f.answers);
  fixed_sensor_v_.store(f.sensor_v);
  if (f.sensor != ModuleFaults::Sensor::kNormal && sensor_.load() == ModuleFaults::Sensor::kNormal) {
    steps_to_safe_.store(-1);
    sensor_fault_step_.store(static_cast<std::int64_t>(steps_done));
  }
  sensor_.store(f.sensor);
}

std::optional<hal::PointWords> InjectedFaults::sensor_words(const hal::AnalogPoint& sensor, double measured_v) const {
  switch (sensor_.load()) {
    case ModuleFaults::Sensor::kNormal: return encode_volts(sensor, measured_v);
    case ModuleFaults::Sensor::kFrozen: return std::nullopt;  // the last reading stays
    case ModuleFaults::Sensor::kFixed: return encode_volts(sensor, fixed_sensor_v_.load());
    case ModuleFaults::Sensor::kNotANumber:
      // float32: NaN on the wire; int16: -32768, the broken-wire code of analog modules.
      return sensor.encoding == hal::AnalogEncoding::kFloat32
                 ? core::encode_f32(std::numeric_limits<float>::quiet_NaN(), sensor.word_order)
                 : hal::PointWords{0x8000, 0};
  }
  return std::nullopt;
}

void InjectedFaults::count_step(std::uint64_t step, double valve_v) {
  if (const std::int64_t at = sensor_fault_step_.load(); at >= 0 && steps_to_safe_.load() < 0 && valve_v == 0.0)
    steps_to_safe_.store(static_cast<long>(static_cast<std::int64_t>(step) - at));
}

}  // namespace epa::rig
