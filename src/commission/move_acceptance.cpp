#include "commission/move_acceptance.hpp"

#include <cmath>
#include <fmt/format.h>
#include <string>

#include "core/format.hpp"

namespace epa::commission {

JudgedMove judge_move(double from_mm, double to_mm, const core::StepMetrics& m, const MoveLimits& limits) {
  JudgedMove j{from_mm, to_mm, m, false, {}};
  const std::string move = fmt::format("move {:.1f} -> {:.1f} mm: ", from_mm, to_mm);
  const double overshoot_mm = m.overshoot_pct ? *m.overshoot_pct / 100.0 * std::abs(to_mm - from_mm) : 0.0;
  if (!m.moved)
    j.why = move + "the piston did not move";
  else if (limits.settling_s > 0.0 && !m.settling_s)
    j.why = move + fmt::format("never settled, limit {:.2f} s", limits.settling_s);
  else if (limits.settling_s > 0.0 && *m.settling_s > limits.settling_s)
    j.why = move + fmt::format("settling {:.2f} s, limit {:.2f} s", *m.settling_s, limits.settling_s);
  else if (m.overshoot_pct && *m.overshoot_pct > limits.overshoot_pct && overshoot_mm > limits.overshoot_mm)
    j.why = move + fmt::format("overshoot {:.1f} % ({:.2f} mm), limit {:.1f} %{}", *m.overshoot_pct, overshoot_mm, limits.overshoot_pct,
                               limits.overshoot_mm > 0.0 ? " or " + core::format_number(limits.overshoot_mm) + " mm" : std::string());
  else if (!(m.ess_mm <= limits.ess_mm))
    j.why = move + fmt::format("e_ss {:.2f} mm, limit {:.2f} mm", m.ess_mm, limits.ess_mm);
  else
    j.passed = true;
  return j;
}

}  // namespace epa::commission
