#pragma once
// The scan cycle's fault checks, one step each, in the order a cycle runs them: I/O failures and
// overruns in a row, a reading no sensor gives, and while the axis is driven (RUN, MANUAL, EXCITE)
// the soft limits, the heartbeat, a frozen reading and, in RUN, the following error. The first
// check that fails names the fault. Between cycles it keeps what the checks need: the failures in
// a row, since when a reading has stood still or an error has lasted, and how far an axis entered
// outside the soft limits has come back. Fixed size, noexcept and allocation-free: it runs in
// every cycle.
#include <cstdint>
#include <limits>

#include "hal/daq.hpp"
#include "runtime/following_watch.hpp"
#include "runtime/mode.hpp"
#include "runtime/runtime_config.hpp"

namespace epa::runtime {

// This cycle as the checks see it, after the sensor was read.
struct CycleView {
  Mode mode = Mode::kStop;
  bool read_ok = false;        // this cycle's reading arrived; the values below are from it if so
  double sensor_v = 0.0;       // the last reading, and the position it gives
  double position_mm = 0.0;
  double valve_v = 0.0;        // last cycle's command: the one the piston has moved under since
  std::int64_t heartbeat_changed_ns = 0;  // when the supervising client last changed the heartbeat
  // RUN: the motion task the following error is measured against, and where the piston is for it
  // (the mean of the last two readings, following_watch.hpp).
  double reference_mm = 0.0, target_mm = 0.0, following_position_mm = 0.0;
};

class FaultDetector {
 public:
  explicit FaultDetector(const RuntimeConfig& config)
      : config_(config), following_(config.period_s) {}

  // What the I/O did, counted as it happens: a read before this cycle's checks (the N-th failure
  // faults in its own cycle), a write for the next cycle's, a deadline between cycles.
  void count_read(const hal::SensorReading& reading) noexcept;
  void count_write(hal::IoStatus status) noexcept;
  void count_deadline(bool missed) noexcept;

  // The first check this cycle fails, or kNone.
  FaultCode check(const CycleView& cycle, std::int64_t now_ns) noexcept;

  // A fault reset (FAULT -> STOP): the failures in a row and the following error start over.
  void reset() noexcept;
  // RUN entered: the following error starts over.
  void restart_following_error() noexcept;
  // RUN or MANUAL entered at `position_mm` outside the soft limits (after a soft-limit fault and
  // its reset): the axis may be brought back in from there.
  void allow_recovery_from(double position_mm) noexcept { soft_limit_recovery_mm_ = position_mm; }
  void hold_soft_limits() noexcept { soft_limit_recovery_mm_ = kNaN; }  // crossing them faults at once
  bool outside_soft_limits(double position_mm) const noexcept {
    return position_mm < config_.soft_min_mm || position_mm > config_.soft_max_mm;
  }

  // The motion the following error is measured against: the scan cycle tells it each task.
  FollowingWatch& following() noexcept { return following_; }

  // For the snapshot and a fault's cause.
  bool following_error_shown() const noexcept { return following_error_shown_; }
  std::uint64_t io_errors() const noexcept { return io_errors_; }  // every failed read and write
  int failed_reads() const noexcept { return consecutive_read_errors_; }  // in a row, up to now
  int failed_writes() const noexcept { return consecutive_write_errors_; }
  hal::IoStatus last_read() const noexcept { return last_read_status_; }
  hal::IoStatus last_write() const noexcept { return last_write_status_; }

 private:
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

  bool io_failing() const noexcept;
  bool overrunning() const noexcept;
  FaultCode implausible(double sensor_v) const noexcept;  // not finite, or out of the sensor's range
  bool left_the_soft_limits(double position_mm) noexcept;
  bool heartbeat_lost(std::int64_t changed_ns, std::int64_t now_ns) const noexcept;
  bool sensor_frozen(const CycleView& cycle, std::int64_t now_ns) noexcept;
  bool following_error_too_long(const CycleView& cycle, std::int64_t now_ns) noexcept;

  const RuntimeConfig config_;
  FollowingWatch following_;
  int consecutive_read_errors_ = 0, consecutive_write_errors_ = 0, consecutive_overruns_ = 0;
  hal::IoStatus last_read_status_ = hal::IoStatus::kOk, last_write_status_ = hal::IoStatus::kOk;
  std::uint64_t io_errors_ = 0;
  double last_good_sensor_v_ = 0.0;  // the last reading that arrived ...
  bool reading_unchanged_ = false;   // ... and whether it was bit-identical to the one before
  std::int64_t frozen_since_ns_ = -1;  // the reading has been bit-identical while driving since then
  std::int64_t following_error_since_ns_ = -1;  // beyond following_error_mm since then; -1: within
  bool following_error_shown_ = false;          // ... for kFollowingErrorShownAfterS: the status bit
  // The innermost position reached since the axis was entered outside the soft limits; NaN: inside.
  double soft_limit_recovery_mm_ = kNaN;
};

}  // namespace epa::runtime
