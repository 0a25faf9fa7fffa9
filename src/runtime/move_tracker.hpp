#pragma once
// One record of each move: from the cycle its target was set in RUN to the cycle it ended (in
// position, halted and braked, cut short, stopped, faulted, its law switched, standing off target
// or judged after move_window_s). Its positions are kept in a buffer allocated once, as long as
// the recorder's ring, and its metrics come from core::move_metrics over exactly those samples,
// the ones its run file holds.
#include <cmath>
#include <cstdint>
#include <memory>
#include <span>

#include "control/controller_kind.hpp"
#include "core/move_metrics.hpp"

namespace epa::runtime {

using core::MoveEnd;

struct MoveResult {
  std::uint32_t number = 0;  // 1 for the first move since start
  double from_mm = 0.0, to_mm = 0.0;
  core::MoveMetrics metrics{};
  MoveEnd end = MoveEnd::kInPosition;
  control::ControllerKind controller = control::ControllerKind::kPpFfidz;  // the law that ran it
  std::uint64_t first_sample = 0, end_sample = 0;  // recorder indices of the move
};

class MoveTracker {
 public:
  // capacity_samples: the recorder ring's length (a move longer than that could not be recorded
  // whole: it is judged, as a timeout, when the buffer is full). judge_after_s: move_window_s.
  MoveTracker(std::size_t capacity_samples, double judge_after_s, double Ts, double ess_window_s)
      : capacity_(capacity_samples),
        judge_after_samples_(static_cast<std::size_t>(std::lround(judge_after_s / Ts))),
        options_{.Ts = Ts, .ess_window_s = ess_window_s},
        y_(std::make_unique<double[]>(capacity_)) {}

  bool active() const noexcept { return active_; }
  const MoveResult& current() const noexcept { return current_; }

  // `from_mm`: the last reading, until the move's first sample replaces it (add()).
  void start(double from_mm, double to_mm, control::ControllerKind law, std::uint64_t sample_index) noexcept {
    active_ = true;
    count_ = since_arrival_ = 0;
    current_ = {next_number_++, from_mm, to_mm, {}, MoveEnd::kInPosition, law, sample_index, sample_index};
  }

  // Adds the position of one cycle. `reference_arrived`: the reference the law follows has
  // reached the target. True when the move must now be judged as a timeout (move_window_s since
  // the reference arrived, or the buffer full).
  bool add(double y_mm, bool reference_arrived) noexcept {
    if (!active_ || count_ >= capacity_) return false;
    // Its first sample is the reading of the cycle it started in: where its record and its run
    // file begin (the reading before, in a move cut short at speed, is a few mm behind).
    if (count_ == 0) current_.from_mm = y_mm;
    y_[count_++] = y_mm;
    current_.end_sample++;
    if (reference_arrived) ++since_arrival_;
    return count_ == capacity_ || since_arrival_ >= judge_after_samples_;
  }

  MoveResult finish(MoveEnd end) noexcept {
    active_ = false;
    current_.end = end;
    current_.metrics = core::move_metrics(std::span<const double>(y_.get(), count_), current_.from_mm, current_.to_mm, end, options_);
    return current_;
  }

  const core::MoveMetricsOptions& options() const noexcept { return options_; }

 private:
  std::size_t capacity_;
  std::size_t judge_after_samples_;
  core::MoveMetricsOptions options_;
  std::unique_ptr<double[]> y_;
  std::size_t count_ = 0, since_arrival_ = 0;
  bool active_ = false;
  std::uint32_t next_number_ = 1;
  MoveResult current_;
};

}  // namespace epa::runtime
