#include "runtime/mode.hpp"

#include <string>

namespace epa::runtime {

std::string_view to_string(Mode mode) {
  switch (mode) {
    case Mode::kStop: return "stop";
    case Mode::kRun: return "run";
    case Mode::kManual: return "manual";
    case Mode::kFault: return "fault";
    case Mode::kExcite: return "excite";
  }
  return "?";
}

std::string_view to_string(FaultCode code) {
  switch (code) {
    case FaultCode::kNone: return "none";
    case FaultCode::kSensorNotFinite: return "sensor-not-finite";
    case FaultCode::kSensorOutOfRange: return "sensor-out-of-range";
    case FaultCode::kSoftLimit: return "soft-limit";
    case FaultCode::kIoErrors: return "io-errors";
    case FaultCode::kOverruns: return "overruns";
    case FaultCode::kFollowingError: return "following-error";
    case FaultCode::kHeartbeatLost: return "heartbeat-lost";
    case FaultCode::kControllerFault: return "controller-fault";
    case FaultCode::kStoreDamaged: return "store-damaged";
    case FaultCode::kSensorFrozen: return "sensor-frozen";
    case FaultCode::kModelHealth: return "model-health";
  }
  return "?";
}

std::string_view describe(FaultCode code) {
  switch (code) {
    case FaultCode::kNone: return "no fault";
    case FaultCode::kSensorNotFinite: return "the position sensor reading is not a number";
    case FaultCode::kSensorOutOfRange: return "the position sensor reading is outside its valid range (wire or scaling)";
    case FaultCode::kSoftLimit: return "the piston left the soft limits";
    case FaultCode::kIoErrors: return "the DAQ failed to read or write several cycles in a row";
    case FaultCode::kOverruns: return "the scan cycle missed its deadline several cycles in a row";
    case FaultCode::kFollowingError: return "the position did not follow the setpoint (following error too large for too long)";
    case FaultCode::kHeartbeatLost: return "the supervising client's heartbeat stopped";
    case FaultCode::kControllerFault: return "the control law produced a non-finite command";
    case FaultCode::kSensorFrozen:
      return "the position reading stopped changing while the valve was driving the piston: a frozen sensor or a stuck input";
    case FaultCode::kModelHealth:
      return "the model-health monitor's warning began, changed or ended; a warning, not a fault: the axis ran on";
    case FaultCode::kStoreDamaged:
      return "the tuning database was damaged: it was moved aside and the appliance started from the seeded defaults; check the tuning, then reset";
  }
  return "unknown fault";
}

core::Result<Mode> parse_mode(std::string_view name) {
  for (Mode m : {Mode::kStop, Mode::kRun, Mode::kManual, Mode::kExcite})
    if (to_string(m) == name) return m;
  return core::invalid_argument("mode '" + std::string(name) + "' is not one of stop, run, manual, excite");
}

}  // namespace epa::runtime
