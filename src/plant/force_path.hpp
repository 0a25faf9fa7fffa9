#pragma once
// How a force on the piston enters the Hammerstein model. The model's B answers the valve's flow
// (the printed B swings the position at the Nyquist rate with every change of the drive); a force
// such as friction does not change the flow, it changes the piston's speed through the mechanics:
// a first-order lag with the slowest real pole p of A' (A = (1 - q^-1) A'), at the model's steady
// speed per volt of drive. In the ARX it is a second input F (volts of drive) through
//   C(q) = k (1 - p) q^-1 A'(q) / (1 - p q^-1),   k = B(1) / A'(1),
// so that C / A = k (1 - p) q^-1 / ((1 - p q^-1)(1 - q^-1)): once steady, a volt of force moves
// the piston as a volt of drive does, without B's swing.
#include <array>
#include <cstddef>

#include "core/hammerstein_model.hpp"

namespace epa::plant {

struct ForcePath {
  std::array<double, core::kMaxModelOrder + 1> c{};  // c[i] multiplies F(k + 1 - i); c[0] = 0
  std::size_t nc = 0;                                // highest i with a coefficient
  double pole = 0.0;                                 // p: 0 when A' has no real pole in (0, 1)
  double speed_mm_s_per_V = 0.0;                     // steady piston speed per volt of drive
};

ForcePath force_path(const core::HammersteinModel& model);

}  // namespace epa::plant
