#pragma once
// A DAQ whose readings and failures the test scripts, and which remembers what was written.
#include <limits>

#include "hal/daq.hpp"
#include "runtime/clock.hpp"

namespace epa::runtime::testing {

class FakeDaq final : public hal::Daq {
 public:
  double sensor_v = 2.0;
  hal::IoStatus read_status = hal::IoStatus::kOk;
  hal::IoStatus write_status = hal::IoStatus::kOk;
  double last_written_v = std::numeric_limits<double>::quiet_NaN();
  int writes = 0;
  VirtualClock* clock = nullptr;  // if set, each read takes `read_takes_ns` of virtual time
  std::int64_t read_takes_ns = 0;

  std::string describe() const override { return "fake"; }
  core::Status open() override { return core::ok(); }
  hal::SensorReading read_sensor() noexcept override {
    if (clock) clock->advance(read_takes_ns);
    return {read_status, sensor_v};
  }
  hal::IoStatus write_valve(double v) noexcept override {
    last_written_v = v;
    ++writes;
    return write_status;
  }
  void close() noexcept override {}
};

}  // namespace epa::runtime::testing
