#pragma once
// The two dead-zone compensations applied to the pole-placement output u (volts), as NOTES.md
// reads the paper. Both are pure functions of the current sample.
#include <cmath>

#include "core/dead_zone.hpp"

namespace epa::control {

// NG-IDZ (conventional, eq 5 on the controller output): u/m_r + b_r for u > 0, u/m_l + b_l for
// u < 0, 0 for u = 0. It jumps across the dead band at every sign change, hence the chatter.
inline double ngidz_command(const core::DeadZone& dz, double u) noexcept { return dz.inverse(u); }

// FF-IDZ (the paper's eq 6-8): u + l_c * SE * [DE (u/m_r + b_r) + (1 - DE) (u/m_l + b_l)].
// SE = 1 whenever the loop is engaged; DE = 1 when e = r - y > 0 (the sign of e, not of u: g0 < 0
// makes the first u point the wrong way); l_c = 1 while |e| > lc_v, so the feed-forward switches
// off near the target and the valve rests inside the dead band instead of chattering.
inline double ffidz_command(const core::DeadZone& dz, double u, double e, double lc_v) noexcept {
  if (!(std::abs(e) > lc_v)) return u;
  return u + (e > 0.0 ? u / dz.m_r + dz.b_r : u / dz.m_l + dz.b_l);
}

}  // namespace epa::control
