#pragma once
// The linear pole-placement law in RST form, F(q) u = H(q) r - G(q) y, with fixed-size storage so
// a step allocates nothing. With H = G (docs/paper.md) it is error feedback F u = G (r - y).
#include <array>
#include <cstddef>

namespace epa::control {

inline constexpr std::size_t kMaxLawOrder = 6;  // highest power of q in F, G or H

struct RstCoefficients {
  std::array<double, kMaxLawOrder + 1> F{}, G{}, H{};  // F[0] = 1 (validated by ControllerParams)
  std::size_t nF = 0, nG = 0, nH = 0;                  // degree of each (index of last coefficient)
};

// Past values, most recent first: u_past[0] = u(k-1), y_past[0] = y(k-1), r_past[0] = r(k-1).
struct RstState {
  std::array<double, kMaxLawOrder> u_past{}, y_past{}, r_past{};
};

// u(k) = H r - G y - (F - 1) u, using r(k), y(k) and the stored past; then shifts the past.
inline double rst_step(const RstCoefficients& c, RstState& s, double r, double y) noexcept {
  double u = c.H[0] * r - c.G[0] * y;
  for (std::size_t i = 1; i <= c.nH; ++i) u += c.H[i] * s.r_past[i - 1];
  for (std::size_t i = 1; i <= c.nG; ++i) u -= c.G[i] * s.y_past[i - 1];
  for (std::size_t i = 1; i <= c.nF; ++i) u -= c.F[i] * s.u_past[i - 1];
  for (std::size_t i = kMaxLawOrder - 1; i > 0; --i) {
    s.u_past[i] = s.u_past[i - 1];
    s.y_past[i] = s.y_past[i - 1];
    s.r_past[i] = s.r_past[i - 1];
  }
  s.u_past[0] = u;
  s.y_past[0] = y;
  s.r_past[0] = r;
  return u;
}

}  // namespace epa::control
