#include "runtime/fault_detector.hpp"

#include <algorithm>
#include <cmath>

namespace epa::runtime {

namespace {
constexpr double kSoftLimitRecoverySlackMm = 1.0;  // outside the soft limits: how far back out a recovery may go (noise)
constexpr double kFrozenEndClearanceMm = 2.0;     // a piston this close to an end of the setpoint range may stand

bool drives_the_axis(Mode mode) { return mode == Mode::kRun || mode == Mode::kManual || mode == Mode::kExcite; }
bool lasted(std::int64_t since_ns, std::int64_t now_ns, double limit_s) {
  return static_cast<double>(now_ns - since_ns) > limit_s * 1e9;
}
}  // namespace

void FaultDetector::count_read(const hal::SensorReading& reading) noexcept {
  last_read_status_ = reading.status;
  if (reading.status != hal::IoStatus::kOk) {
    ++consecutive_read_errors_;
    ++io_errors_;
    return;
  }
  consecutive_read_errors_ = 0;
  reading_unchanged_ = reading.sensor_v == last_good_sensor_v_;
  last_good_sensor_v_ = reading.sensor_v;
}

void FaultDetector::count_write(hal::IoStatus status) noexcept {
  last_write_status_ = status;
  if (status == hal::IoStatus::kOk) {
    consecutive_write_errors_ = 0;
  } else {
    ++consecutive_write_errors_;  // a valve that cannot be written faults at the next cycle's check
    ++io_errors_;
  }
}

void FaultDetector::count_deadline(bool missed) noexcept { consecutive_overruns_ = missed ? consecutive_overruns_ + 1 : 0; }

FaultCode FaultDetector::check(const CycleView& c, std::int64_t now_ns) noexcept {
  if (io_failing()) return FaultCode::kIoErrors;
  if (overrunning()) return FaultCode::kOverruns;
  if (c.read_ok) {
    if (const FaultCode f = implausible(c.sensor_v); f != FaultCode::kNone) return f;
  }
  if (!drives_the_axis(c.mode)) return FaultCode::kNone;
  if (c.read_ok && left_the_soft_limits(c.position_mm)) return FaultCode::kSoftLimit;
  if (heartbeat_lost(c.heartbeat_changed_ns, now_ns)) return FaultCode::kHeartbeatLost;
  if (c.read_ok && sensor_frozen(c, now_ns)) return FaultCode::kSensorFrozen;
  if (c.mode == Mode::kRun && c.read_ok && following_error_too_long(c, now_ns)) return FaultCode::kFollowingError;
  return FaultCode::kNone;
}

void FaultDetector::reset() noexcept {
  consecutive_read_errors_ = consecutive_write_errors_ = consecutive_overruns_ = 0;
  restart_following_error();
}

void FaultDetector::restart_following_error() noexcept {
  following_error_since_ns_ = -1;
  following_error_shown_ = false;
}

bool FaultDetector::io_failing() const noexcept {
  return consecutive_read_errors_ >= config_.max_consecutive_io_errors ||
         consecutive_write_errors_ >= config_.max_consecutive_io_errors;
}

bool FaultDetector::overrunning() const noexcept { return consecutive_overruns_ >= config_.max_consecutive_overruns; }

FaultCode FaultDetector::implausible(double sensor_v) const noexcept {
  if (!std::isfinite(sensor_v)) return FaultCode::kSensorNotFinite;
  if (sensor_v < config_.sensor_min_v || sensor_v > config_.sensor_max_v) return FaultCode::kSensorOutOfRange;
  return FaultCode::kNone;
}

// Entered outside (a soft-limit fault, then reset): the axis may be brought back in, by a jog, the
// manual valve or a move; going 1 mm further out than the innermost point it reached since is the
// fault again. Crossing the limit from inside is the fault at once, as always.
bool FaultDetector::left_the_soft_limits(double position_mm) noexcept {
  if (!outside_soft_limits(position_mm)) {
    soft_limit_recovery_mm_ = kNaN;  // inside: the limits hold from here
    return false;
  }
  if (std::isnan(soft_limit_recovery_mm_)) return true;
  const bool above = position_mm > config_.soft_max_mm;
  soft_limit_recovery_mm_ = above ? std::min(soft_limit_recovery_mm_, position_mm) : std::max(soft_limit_recovery_mm_, position_mm);
  return std::abs(position_mm - soft_limit_recovery_mm_) > kSoftLimitRecoverySlackMm;
}

bool FaultDetector::heartbeat_lost(std::int64_t changed_ns, std::int64_t now_ns) const noexcept {
  return config_.heartbeat_timeout_s > 0.0 && lasted(changed_ns, now_ns, config_.heartbeat_timeout_s);
}

// A reading bit-identical to the one before while the valve drives the piston beyond the dead
// band, away from the ends of the setpoint range, where it must move.
bool FaultDetector::sensor_frozen(const CycleView& c, std::int64_t now_ns) noexcept {
  if (!(config_.sensor_frozen_time_s > 0.0)) return false;  // off
  const bool driving = std::abs(c.valve_v) > config_.sensor_frozen_drive_v &&
                       c.position_mm > config_.setpoint_min_mm + kFrozenEndClearanceMm &&
                       c.position_mm < config_.setpoint_max_mm - kFrozenEndClearanceMm;
  if (!driving || !reading_unchanged_) {
    frozen_since_ns_ = -1;
    return false;
  }
  if (frozen_since_ns_ < 0) frozen_since_ns_ = now_ns;
  return static_cast<double>(now_ns - frozen_since_ns_) >= config_.sensor_frozen_time_s * 1e9;
}

bool FaultDetector::following_error_too_long(const CycleView& c, std::int64_t now_ns) noexcept {
  if (!(config_.following_error_time_s > 0.0)) return false;  // off
  if (!(following_.step(c.reference_mm, c.target_mm, c.following_position_mm) > config_.following_error_mm)) {
    restart_following_error();
    return false;
  }
  if (following_error_since_ns_ < 0) following_error_since_ns_ = now_ns;
  const auto for_ns = static_cast<double>(now_ns - following_error_since_ns_);
  following_error_shown_ = for_ns >= kFollowingErrorShownAfterS * 1e9;
  return for_ns > config_.following_error_time_s * 1e9;
}

}  // namespace epa::runtime
