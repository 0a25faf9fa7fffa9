#include "core/stick_slip_params.hpp"

#include <cmath>
#include <string>
#include <utility>

namespace epa::core {

namespace {

Status need(bool ok, const char* field, const char* what) {
  if (ok) return core::ok();
  return invalid_argument(std::string("stick-slip model: ") + field + " " + what);
}

}  // namespace

Status StickSlipParams::validate() const {
  const auto finite = [](double x) { return std::isfinite(x); };
  if (auto s = need(finite(break_right_v) && break_right_v >= 0.0, "break_right_v", "must be finite and >= 0"); !s) return s;
  if (auto s = need(finite(break_left_v) && break_left_v <= 0.0, "break_left_v", "must be finite and <= 0"); !s) return s;
  if (auto s = need(finite(speed_right_mm_s_per_v) && speed_right_mm_s_per_v > 0.0, "speed_right_mm_s_per_v", "must be > 0");
      !s)
    return s;
  if (auto s = need(finite(speed_left_mm_s_per_v) && speed_left_mm_s_per_v > 0.0, "speed_left_mm_s_per_v", "must be > 0"); !s)
    return s;
  if (auto s = need(finite(spring_rad_s) && spring_rad_s > 0.0, "spring_rad_s", "must be > 0"); !s) return s;
  if (auto s = need(finite(damping_ratio) && damping_ratio >= 0.0, "damping_ratio", "must be >= 0"); !s) return s;
  if (auto s = need(finite(coulomb_mm) && coulomb_mm >= 0.0, "coulomb_mm", "must be >= 0"); !s) return s;
  if (auto s = need(finite(static_mm) && static_mm >= coulomb_mm, "static_mm", "must be >= coulomb_mm"); !s) return s;
  if (auto s = need(finite(spool_lag_s) && spool_lag_s >= 0.0, "spool_lag_s", "must be >= 0"); !s) return s;
  return need(delay_samples >= 0 && delay_samples <= kMaxDelay, "delay_samples", "must be within 0..8");
}

Status StickSlipSpread::validate() const {
  for (const auto& [name, member] : kStickSlipSpreadFields)
    if (const double v = this->*member; !(std::isfinite(v) && v >= 0.0))
      return invalid_argument("stick-slip spread: " + std::string(name) + " must be finite and >= 0");
  return ok();
}

}  // namespace epa::core
