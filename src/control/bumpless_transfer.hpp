#pragma once
// Bumpless transfer between two control laws (or two tunings of one): at the switch the new law's
// valve command is offset to equal the command the valve already holds, and the offset decays to
// zero over a few samples, so the valve never steps at a switch; the new law then acts alone.
// Allocation-free, noexcept, in valve volts.
#include <cmath>

namespace epa::control {

class BumplessTransfer {
 public:
  // time_constant_s: how fast the new law takes over (the offset falls to 1/e in this time).
  explicit BumplessTransfer(double time_constant_s = 0.05, double Ts = 0.005) noexcept
      : decay_(time_constant_s > 0.0 ? std::exp(-Ts / time_constant_s) : 0.0) {}

  // At the switch: the valve holds `held_v`, the new law asks `new_v` in its first sample.
  void start(double held_v, double new_v) noexcept {
    offset_v_ = std::isfinite(held_v) && std::isfinite(new_v) ? held_v - new_v : 0.0;
    held_v_ = held_v;
    first_ = offset_v_ != 0.0;
  }

  // Every sample: the new law's command with what is left of the offset (exactly `held_v` in the
  // sample of start()).
  double apply(double new_v) noexcept {
    const double out = first_ ? held_v_ : new_v + offset_v_;  // new + (held - new) may miss held by an ulp
    first_ = false;
    offset_v_ *= decay_;
    if (std::abs(offset_v_) < 1e-6) offset_v_ = 0.0;
    return out;
  }

  bool active() const noexcept { return offset_v_ != 0.0; }

 private:
  double decay_;
  double offset_v_ = 0.0;
  double held_v_ = 0.0;
  bool first_ = false;
};

}  // namespace epa::control
