#include "diag/sensor_resolution.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace epa::diag {

std::optional<double> reading_resolution_mm(const std::vector<const core::Run*>& runs) {
  // The candidate step: the smallest change between consecutive readings (a quantised reading
  // changes by whole steps only; a continuous one by arbitrarily little).
  double step = 0.0;
  for (const auto* r : runs)
    for (std::size_t k = 1; k < r->y_mm.size(); ++k) {
      const double d = std::abs(r->y_mm[k] - r->y_mm[k - 1]);
      if (d > 1e-9 && (step == 0.0 || d < step)) step = d;
    }
  if (step <= 0.0) return std::nullopt;
  // The smallest change carries the rounding of the file's decimals (a 10-bit sensor's 0.48876 mm
  // written as 0.4888 or 0.4887); far from the origin that error adds up to more than the
  // tolerance, so the step is refined by least squares over the levels the readings sit on.
  for (int pass = 0; pass < 2; ++pass) {
    double num = 0.0, den = 0.0;
    for (const auto* r : runs) {
      if (r->y_mm.empty()) continue;
      for (double y : r->y_mm) {
        const double n = std::round((y - r->y_mm.front()) / step);
        num += n * (y - r->y_mm.front()), den += n * n;
      }
    }
    if (den > 0.0) step = num / den;
  }
  std::size_t on_grid = 0, total = 0;
  std::set<long long> levels;
  for (const auto* r : runs) {
    if (r->y_mm.empty()) continue;
    const double origin = r->y_mm.front();
    for (double y : r->y_mm) {
      const double n = (y - origin) / step;
      on_grid += std::abs(n - std::round(n)) < 0.01;
      ++total;
      if (levels.size() < 10) levels.insert(std::llround(n));
    }
  }
  if (total == 0 || static_cast<double>(on_grid) < 0.99 * static_cast<double>(total) || levels.size() < 10) return std::nullopt;
  return step;
}

}  // namespace epa::diag
