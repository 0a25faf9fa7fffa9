#pragma once
// The position sensor's scale. The control law works in sensor volts; everything above it (points,
// store, files, pages) in mm. A conversion between the two above the law goes through here, so the
// scale travels as one value and not as a loose number beside the quantity.
#include "core/units.hpp"

namespace epa::core {

struct SensorCalibration {
  double mm_per_volt = kMmPerSensorVolt;

  constexpr double to_volts(double mm) const noexcept { return mm / mm_per_volt; }
  constexpr double to_mm(double volts) const noexcept { return volts * mm_per_volt; }
};

}  // namespace epa::core
