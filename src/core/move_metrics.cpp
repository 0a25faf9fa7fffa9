#include "core/move_metrics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace epa::core {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::array<std::string_view, kMoveEnds> kNames = {"in_position", "cut_short", "halted", "stopped",
                                                            "fault", "controller_switched", "timeout", "off_target"};

// The move was let to run to its own end: only then can it be said to have settled.
bool let_to_end(MoveEnd end) { return end == MoveEnd::kInPosition || end == MoveEnd::kTimeout || end == MoveEnd::kOffTarget; }
}  // namespace

std::string_view to_string(MoveEnd end) {
  const auto i = static_cast<std::size_t>(end);
  return i < kNames.size() ? kNames[i] : "?";
}

std::optional<MoveEnd> parse_move_end(std::string_view name) {
  for (std::size_t i = 0; i < kNames.size(); ++i)
    if (kNames[i] == name) return static_cast<MoveEnd>(i);
  return std::nullopt;
}

MoveMetrics move_metrics(std::span<const double> y_mm, double from_mm, double target_mm, MoveEnd end,
                         const MoveMetricsOptions& o) {
  MoveMetrics m{kNaN, kNaN, kNaN, kNaN};
  const std::size_t n = y_mm.size();
  if (n == 0 || !(o.Ts > 0.0)) return m;
  const bool halted = end == MoveEnd::kHalted, ended = let_to_end(end);

  if (ended) {
    const std::size_t window = std::clamp<std::size_t>(static_cast<std::size_t>(std::lround(o.ess_window_s / o.Ts)), 1, n);
    double sum = 0.0;
    for (std::size_t k = n - window; k < n; ++k) sum += std::abs(target_mm - y_mm[k]);
    m.ess_mm = sum / static_cast<double>(window);
  }

  const double length = std::abs(target_mm - from_mm);
  if (!(length > 0.0)) return m;  // no way to go: nothing to rise, settle or overshoot
  const double direction = target_mm > from_mm ? 1.0 : -1.0;
  const double band = o.settling_band * length;
  std::optional<std::size_t> k_low, k_high, last_outside;
  double furthest = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < n; ++k) {
    const double progress = direction * (y_mm[k] - from_mm);
    if (!k_low && progress >= 0.1 * length) k_low = k;
    if (!k_high && progress >= 0.9 * length) k_high = k;
    furthest = std::max(furthest, progress);
    if (std::abs(y_mm[k] - target_mm) > band) last_outside = k;
  }
  if (k_low && k_high) m.rise_s = static_cast<double>(*k_high - *k_low) * o.Ts;
  if (!halted && (ended || furthest > length)) m.overshoot_pct = std::max(0.0, furthest - length) / length * 100.0;
  if (ended) {
    if (!last_outside) m.settling_s = 0.0;
    else if (*last_outside + 1 < n) m.settling_s = static_cast<double>(*last_outside + 1) * o.Ts;
  }
  return m;
}

}  // namespace epa::core
