#include "core/dead_zone.hpp"

#include <cmath>
#include <string>

namespace epa::core {

Status DeadZone::validate() const {
  const struct { const char* name; double value; } fields[] = {
      {"m_r", m_r}, {"m_l", m_l}, {"b_r", b_r}, {"b_l", b_l}};
  for (const auto& f : fields) {
    if (!std::isfinite(f.value))
      return invalid_argument(std::string("dead zone: ") + f.name + " is not a finite number");
  }
  if (m_r <= 0.0) return invalid_argument("dead zone: slope m_r must be > 0, got " + std::to_string(m_r));
  if (m_l <= 0.0) return invalid_argument("dead zone: slope m_l must be > 0, got " + std::to_string(m_l));
  if (b_l > b_r)
    return invalid_argument("dead zone: left break point b_l (" + std::to_string(b_l) +
                            " V) must not exceed right break point b_r (" + std::to_string(b_r) + " V)");
  return ok();
}

}  // namespace epa::core
