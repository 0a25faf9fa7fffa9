#include "core/step_metrics.hpp"

#include <algorithm>
#include <cmath>

namespace epa::core {

StepMetrics step_metrics(std::span<const double> y_mm, double r_mm, const StepMetricsOptions& o) {
  StepMetrics m;
  const std::size_t n = y_mm.size();
  if (n == 0 || !(o.Ts > 0.0)) return m;

  const std::size_t window = std::clamp<std::size_t>(static_cast<std::size_t>(std::lround(o.ess_window_s / o.Ts)), 1, n);
  double sum_y = 0.0, sum_e = 0.0;
  for (std::size_t k = n - window; k < n; ++k) {
    sum_y += y_mm[k];
    sum_e += std::abs(r_mm - y_mm[k]);
  }
  m.final_mm = sum_y / static_cast<double>(window);
  m.ess_mm = sum_e / static_cast<double>(window);

  const double y0 = y_mm[0];
  const double move = m.final_mm - y0;
  m.moved = std::abs(move) > o.settling_band * std::abs(r_mm - y0) && move != 0.0;
  if (!m.moved) return m;

  // Compared in mm, not as a ratio to the move, so a sample exactly on a band edge lands on the
  // side the definition says (a ratio like 98/100 - 1 rounds past 0.02).
  const double direction = move > 0.0 ? 1.0 : -1.0;
  const double size = std::abs(move);
  const double band = o.settling_band * size;
  std::optional<std::size_t> k_low, k_high, last_outside;
  double peak = 0.0;  // furthest progress towards and beyond the final value, mm
  for (std::size_t k = 0; k < n; ++k) {
    const double progress = direction * (y_mm[k] - y0);
    if (!k_low && progress >= o.rise_low * size) k_low = k;
    if (!k_high && progress >= o.rise_high * size) k_high = k;
    peak = std::max(peak, progress);
    if (std::abs(y_mm[k] - m.final_mm) > band) last_outside = k;
  }
  if (k_low && k_high) m.rise_s = static_cast<double>(*k_high - *k_low) * o.Ts;
  if (!last_outside) m.settling_s = 0.0;
  else if (*last_outside + 1 < n) m.settling_s = static_cast<double>(*last_outside + 1) * o.Ts;
  m.overshoot_pct = std::max(0.0, peak - size) / size * 100.0;
  return m;
}

}  // namespace epa::core
