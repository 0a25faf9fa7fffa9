#pragma once
// Operating modes and fault causes of the appliance, with the names shown in logs, registers
// and the status page. Numeric values are part of the Modbus interface: append, never renumber.
#include <cstdint>
#include <string_view>

#include "core/result.hpp"

namespace epa::runtime {

enum class Mode : std::uint8_t {
  kStop = 0,    // valve at its safe command, controller idle
  kRun = 1,     // closed loop on the setpoint
  kManual = 2,  // open-loop valve command within the manual limit
  kFault = 3,   // latched: valve safe until an explicit reset
  kExcite = 4,  // the open-loop identification experiment; back to STOP by itself when it ends
};

enum class FaultCode : std::uint8_t {
  kNone = 0,
  kSensorNotFinite = 1,   // the sensor reading is NaN or infinite
  kSensorOutOfRange = 2,  // outside [sensor_min_v, sensor_max_v]: broken wire, wrong scaling
  kSoftLimit = 3,         // position outside the soft limits while moving
  kIoErrors = 4,          // consecutive DAQ read or write failures
  kOverruns = 5,          // consecutive cycles that missed their deadline
  kFollowingError = 6,    // |setpoint - position| too large for too long in RUN
  kHeartbeatLost = 7,     // the supervising client stopped incrementing the heartbeat
  kControllerFault = 8,   // the control law reported a non-finite result
  kStoreDamaged = 9,      // the tuning database was damaged: moved aside, started from defaults
  kSensorFrozen = 10,     // the reading stopped changing while the valve drove the piston
  kModelHealth = 11,      // not a fault: a model-health warning began, changed or ended (the fault history only; never latched)
};

std::string_view to_string(Mode mode);
std::string_view to_string(FaultCode code);
std::string_view describe(FaultCode code);  // a sentence for an operator
core::Result<Mode> parse_mode(std::string_view name);  // "stop", "run", "manual", "excite"

}  // namespace epa::runtime
