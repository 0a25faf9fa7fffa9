#pragma once
// What lies between the controller's output and the valve in a robustness check: a transport
// delay of whole samples (a slow fieldbus, a computation that misses its slot) and a first-order
// lag (a valve slower than the model). Fixed storage, allocation-free.
#include <array>
#include <cstddef>

#include "core/first_order_lag.hpp"

namespace epa::sim {

inline constexpr std::size_t kMaxDelaySamples = 32;

struct ValveLineOptions {
  std::size_t delay_samples = 0;  // 0..kMaxDelaySamples
  double lag_s = 0.0;             // first-order time constant; 0: none
};

class ValveLine {
 public:
  ValveLine(const ValveLineOptions& o, double Ts) : delay_(o.delay_samples), alpha_(core::lag_step_share(o.lag_s, Ts)) {}

  // The command the valve sees this sample, given the controller's command now.
  double pass(double command_v) noexcept {
    double out = command_v;
    if (delay_ > 0) {
      out = ring_[next_];
      ring_[next_] = command_v;
      next_ = (next_ + 1) % delay_;
    }
    if (alpha_ >= 1.0) return out;  // no lag: the command itself, bit for bit
    lagged_ += alpha_ * (out - lagged_);
    return lagged_;
  }

 private:
  std::size_t delay_;
  double alpha_;
  std::array<double, kMaxDelaySamples> ring_{};
  std::size_t next_ = 0;
  double lagged_ = 0.0;
};

}  // namespace epa::sim
