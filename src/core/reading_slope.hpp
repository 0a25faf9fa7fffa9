#pragma once
// The least-squares slope of the last four evenly spaced readings, newest first (y[0] the newest),
// per second: (3 y0 + y1 - y2 - 3 y3) / (10 Ts). How the sliding approach reads the piston's speed,
// and so how every model of a coast must read it to predict that law's stop.
#include <array>

namespace epa::core {

inline double slope_of_last_four(const std::array<double, 4>& y, double Ts) noexcept {
  return (3.0 * y[0] + y[1] - y[2] - 3.0 * y[3]) / (10.0 * Ts);
}

}  // namespace epa::core
