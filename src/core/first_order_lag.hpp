#pragma once
// A first-order lag sampled every Ts moves its output this share of the way to its input each
// sample: 1 - exp(-Ts / tau), and 1 (the input itself) for tau <= 0. One rule for every lag that
// is written as a time constant: the valve's lag in the plant and in the robustness simulation, and
// the trajectory law's error filter.
#include <cmath>

namespace epa::core {

inline double lag_step_share(double tau_s, double Ts) noexcept { return tau_s > 0.0 ? 1.0 - std::exp(-Ts / tau_s) : 1.0; }

}  // namespace epa::core
