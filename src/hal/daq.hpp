#pragma once
// The DAQ hardware-abstraction layer: the scan cycle reads the position sensor and writes the
// valve through this interface only, and never knows which backend it talks to (ros2_control's
// read()/write() split). src/app chooses the backend from the configuration.
//
// Lifecycle: open() once outside the loop (may block, may allocate); then read_sensor() and
// write_valve() once per cycle (must not allocate, must return within a bounded time well under
// the period, and report trouble as a status, never by throwing); close() at shutdown.
#include <string>

#include "core/result.hpp"

namespace epa::hal {

enum class IoStatus {
  kOk,
  kTimeout,  // no answer in time (remote I/O); the cycle counts it towards an I/O fault
  kError,    // the device or link reported an error, or the value could not be decoded
};
const char* to_string(IoStatus s);

struct SensorReading {
  IoStatus status = IoStatus::kError;
  double sensor_v = 0.0;  // position sensor voltage (0-10 V over the stroke), valid when kOk
};

class Daq {
 public:
  virtual ~Daq() = default;
  virtual std::string describe() const = 0;  // for logs: backend and where it connects
  virtual core::Status open() = 0;
  virtual SensorReading read_sensor() noexcept = 0;
  virtual IoStatus write_valve(double valve_v) noexcept = 0;
  virtual void close() noexcept = 0;
};

}  // namespace epa::hal
