#pragma once
// The dead-zone compensations applied to the pole-placement output u (volts), as docs/paper.md
// reads the paper. Both are pure functions of the current sample.
#include <algorithm>
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

// pp-traj's inverse: NG-IDZ with its jump across the dead band spread over |u| < ramp, so a small
// u opens the valve a little instead of snapping it to a break point: b_r (u / ramp) + u / m_r for
// 0 <= u < ramp, continuous at 0 and at ramp; ramp = 0 is NG-IDZ.
inline double smooth_idz_command(const core::DeadZone& dz, double u, double ramp) noexcept {
  const double spread = ramp > 0.0 ? std::min(std::abs(u) / ramp, 1.0) : 1.0;
  if (u > 0.0) return u / dz.m_r + dz.b_r * spread;
  if (u < 0.0) return u / dz.m_l + dz.b_l * spread;
  return 0.0;
}

// pp-traj once its profile has arrived: NG-IDZ with its jump stopping `margin_v` short of each
// break point, the rest crossed linearly (the break point reached at u = m margin_v, valve
// 2 u / m + b - margin_v there). A break point that is really up to margin_v nearer to 0 than the
// model's cannot turn the last millimetre into a bang-bang between b_l and b_r (NG-IDZ's chatter),
// and a piston held by static friction is loaded gradually until it breaks away.
inline double creeping_idz_command(const core::DeadZone& dz, double u, double margin_v) noexcept {
  if (u > 0.0) return u / dz.m_r + std::max(0.0, dz.b_r - margin_v) + std::min(u / dz.m_r, std::min(margin_v, dz.b_r));
  if (u < 0.0) return u / dz.m_l + std::min(0.0, dz.b_l + margin_v) + std::max(u / dz.m_l, -std::min(margin_v, -dz.b_l));
  return 0.0;
}

}  // namespace epa::control
