#pragma once
// The valve's asymmetric dead zone (paper eq 2) and its inverse (eq 5). Shared by the plant
// (which applies it) and the controllers (which invert it), hence in core.
#include <iterator>
#include <string_view>

#include "core/result.hpp"

namespace epa::core {

// Its fields' names, in field order: the keys of the [dead_zone] table in the model file and the
// tuning file alike (docs/formats.md), and the names validate() gives.
inline constexpr std::string_view kDeadZoneKeys[] = {"m_r", "m_l", "b_r", "b_l"};

struct DeadZone {
  double m_r = 1.0;  // right slope (valve volts in -> effective volts out), > 0
  double m_l = 1.0;  // left slope, > 0
  double b_r = 0.0;  // right break point, V (>= b_l)
  double b_l = 0.0;  // left break point, V

  // Checks slopes > 0, b_l <= b_r, everything finite; the message names the offending field.
  Status validate() const;

  // Eq 2: u_d = m_l (u - b_l) below b_l, 0 inside [b_l, b_r], m_r (u - b_r) above b_r.
  double apply(double u_v) const {
    if (u_v > b_r) return m_r * (u_v - b_r);
    if (u_v < b_l) return m_l * (u_v - b_l);
    return 0.0;
  }

  // Eq 5: the valve command that makes apply() produce u_d; 0 for u_d == 0.
  double inverse(double u_d) const {
    if (u_d > 0.0) return u_d / m_r + b_r;
    if (u_d < 0.0) return u_d / m_l + b_l;
    return 0.0;
  }

  bool operator==(const DeadZone&) const = default;
};

// The members kDeadZoneKeys name, in the same order: the one list that validate(), the files'
// readers and their writers walk, so that a field cannot be left out of one of them.
inline constexpr double DeadZone::*kDeadZoneMembers[] = {&DeadZone::m_r, &DeadZone::m_l, &DeadZone::b_r, &DeadZone::b_l};
static_assert(std::size(kDeadZoneMembers) == std::size(kDeadZoneKeys));

}  // namespace epa::core
