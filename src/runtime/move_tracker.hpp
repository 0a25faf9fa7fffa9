#pragma once
// Online step metrics: after each setpoint change in RUN, the positions of that move are kept in
// a buffer allocated once, and when the move's window is full (or the next move starts) the same
// step_metrics() that `epa simulate` uses is computed over it.
#include <cmath>
#include <cstdint>
#include <memory>

#include "core/step_metrics.hpp"

namespace epa::runtime {

// How a move ended. Numeric values are part of the Modbus interface (move_end): append only.
enum class MoveEnd : std::uint8_t {
  kComplete = 0,  // measured over its whole window
  kCutShort = 1,  // a new target (setpoint or start) came first
  kHalted = 2,    // a halt
  kStopped = 3,   // the mode changed (STOP, MANUAL) or the appliance shut down
  kFault = 4,     // a fault
  kControllerSwitched = 5,  // another controller took over: the move is its first controller's alone
};

struct MoveResult {
  std::uint32_t number = 0;  // 1 for the first move since start
  double from_mm = 0.0, to_mm = 0.0;
  core::StepMetrics metrics;
  MoveEnd end = MoveEnd::kComplete;
  std::uint64_t first_sample = 0, end_sample = 0;  // recorder indices of the move
};

class MoveTracker {
 public:
  MoveTracker(double window_s, double Ts)
      : capacity_(static_cast<std::size_t>(std::lround(window_s / Ts))), Ts_(Ts), y_(std::make_unique<double[]>(capacity_)) {}

  bool active() const noexcept { return active_; }

  void start(double from_mm, double to_mm, std::uint64_t sample_index) noexcept {
    active_ = true;
    count_ = 0;
    current_ = {next_number_++, from_mm, to_mm, {}, MoveEnd::kComplete, sample_index, sample_index};
  }

  // Adds the position of one cycle; true when the window just became full (call finish()).
  bool add(double y_mm) noexcept {
    if (!active_ || count_ >= capacity_) return false;
    y_[count_++] = y_mm;
    current_.end_sample++;
    return count_ == capacity_;
  }

  // The move's metrics over the samples it had. The steady-state window is the last 2 s of a full
  // window, and the last 40 % of a move cut short (its whole length would average the transient
  // in: a move that settled within 1 mm before it was cut reported an 18 mm e_ss).
  MoveResult finish(MoveEnd end) noexcept {
    active_ = false;
    const double length_s = static_cast<double>(count_) * Ts_;
    current_.end = end;
    current_.metrics = core::step_metrics(std::span<const double>(y_.get(), count_), current_.to_mm,
                                          {.Ts = Ts_, .ess_window_s = std::min(2.0, 0.4 * length_s)});
    return current_;
  }

 private:
  std::size_t capacity_;
  double Ts_;
  std::unique_ptr<double[]> y_;
  std::size_t count_ = 0;
  bool active_ = false;
  std::uint32_t next_number_ = 1;
  MoveResult current_;
};

}  // namespace epa::runtime
