#include "core/dead_zone.hpp"

#include <cmath>
#include <iterator>
#include <string>

namespace epa::core {

Status DeadZone::validate() const {
  for (std::size_t i = 0; i < std::size(kDeadZoneMembers); ++i) {
    if (!std::isfinite(this->*kDeadZoneMembers[i]))
      return invalid_argument("dead zone: " + std::string(kDeadZoneKeys[i]) + " is not a finite number");
  }
  if (m_r <= 0.0) return invalid_argument("dead zone: slope m_r must be > 0, got " + std::to_string(m_r));
  if (m_l <= 0.0) return invalid_argument("dead zone: slope m_l must be > 0, got " + std::to_string(m_l));
  if (b_l > b_r)
    return invalid_argument("dead zone: left break point b_l (" + std::to_string(b_l) +
                            " V) must not exceed right break point b_r (" + std::to_string(b_r) + " V)");
  return ok();
}

}  // namespace epa::core
