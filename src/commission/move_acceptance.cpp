#include "commission/move_acceptance.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/format.hpp"

namespace epa::commission {

JudgedMove judge_move(double from_mm, double to_mm, const core::StepMetrics& m, const MoveLimits& limits) {
  JudgedMove j{from_mm, to_mm, m, false, {}};
  char buf[200];
  const double overshoot_mm = m.overshoot_pct ? *m.overshoot_pct / 100.0 * std::abs(to_mm - from_mm) : 0.0;
  if (!m.moved)
    std::snprintf(buf, sizeof buf, "move %.1f -> %.1f mm: the piston did not move", from_mm, to_mm);
  else if (limits.settling_s > 0.0 && !m.settling_s)
    std::snprintf(buf, sizeof buf, "move %.1f -> %.1f mm: never settled, limit %.2f s", from_mm, to_mm, limits.settling_s);
  else if (limits.settling_s > 0.0 && *m.settling_s > limits.settling_s)
    std::snprintf(buf, sizeof buf, "move %.1f -> %.1f mm: settling %.2f s, limit %.2f s", from_mm, to_mm, *m.settling_s,
                  limits.settling_s);
  else if (m.overshoot_pct && *m.overshoot_pct > limits.overshoot_pct && overshoot_mm > limits.overshoot_mm)
    std::snprintf(buf, sizeof buf, "move %.1f -> %.1f mm: overshoot %.1f %% (%.2f mm), limit %.1f %%%s", from_mm, to_mm,
                  *m.overshoot_pct, overshoot_mm, limits.overshoot_pct,
                  limits.overshoot_mm > 0.0 ? (" or " + core::format_number(limits.overshoot_mm) + " mm").c_str() : "");
  else if (!(m.ess_mm <= limits.ess_mm))
    std::snprintf(buf, sizeof buf, "move %.1f -> %.1f mm: e_ss %.2f mm, limit %.2f mm", from_mm, to_mm, m.ess_mm, limits.ess_mm);
  else
    return j.passed = true, j;
  j.why = buf;
  return j;
}

}  // namespace epa::commission
