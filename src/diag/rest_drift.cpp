#include "diag/rest_drift.hpp"

#include <algorithm>
#include <cmath>

namespace epa::diag {

namespace {

struct Line {
  double speed = 0;                // per second
  double mean_t = 0, mean_y = 0;   // the line passes through (mean_t, mean_y); t from the first sample
  std::size_t used = 0;
  double at(double t) const { return mean_y + speed * (t - mean_t); }
};

// Least-squares line through y[first, last) at times k Ts, leaving out the samples `keep` rejects.
template <class Keep>
Line fit_line(const std::vector<double>& y, std::size_t first, std::size_t last, double Ts, Keep keep) {
  double n = 0, st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t k = first; k < last; ++k) {
    if (!keep(k)) continue;
    const double t = static_cast<double>(k - first) * Ts;
    n += 1, st += t, sy += y[k], stt += t * t, sty += t * y[k];
  }
  const double det = n * stt - st * st;
  if (n < 3 || det <= 0) return {};
  return {(n * sty - st * sy) / det, st / n, sy / n, static_cast<std::size_t>(n)};
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

RestDrift rest_drift(const std::vector<const core::Run*>& runs, const core::DeadZone& dz, double noise_std_mm,
                     const RestDriftOptions& o) {
  std::vector<double> speeds, standard_errors;
  for (const auto* r : runs) {
    const auto& y = r->y_mm;
    const auto& u = r->u_V;
    const double Ts = r->Ts;
    const auto settle = static_cast<std::size_t>(std::ceil(o.settle_s / Ts));
    const auto min_length = static_cast<std::size_t>(std::ceil(o.min_rest_s / Ts));
    auto inside = [&](std::size_t k) { return u[k] > dz.b_l + o.margin_V && u[k] < dz.b_r - o.margin_V; };
    for (std::size_t k = 0; k < r->size();) {
      if (!inside(k)) {
        ++k;
        continue;
      }
      std::size_t end = k;
      while (end < r->size() && inside(end)) ++end;
      const std::size_t first = k + settle;
      k = end;
      if (first >= end || end - first < min_length) continue;
      // Twice: the second fit leaves out readings far off the first line (a sensor's spikes).
      const Line rough = fit_line(y, first, end, Ts, [](std::size_t) { return true; });
      const double limit = o.outlier_sigmas * std::max(noise_std_mm, 1e-6);
      auto near_line = [&](std::size_t i) { return std::abs(y[i] - rough.at(static_cast<double>(i - first) * Ts)) <= limit; };
      const Line line = fit_line(y, first, end, Ts, near_line);
      if (line.used < min_length) continue;
      const double n = static_cast<double>(line.used);
      speeds.push_back(std::abs(line.speed));
      // The standard error of a least-squares slope over n evenly spaced readings with white noise.
      standard_errors.push_back(noise_std_mm * std::sqrt(12.0 / (n * (n * n - 1.0))) / Ts);
    }
  }
  RestDrift d;
  d.rests = speeds.size();
  d.median_speed_mm_s = median(speeds);
  d.threshold_mm_s = std::max(o.min_speed_mm_s, o.noise_factor * median(standard_errors));
  d.moving = d.rests >= o.min_rests && d.median_speed_mm_s > d.threshold_mm_s;
  return d;
}

}  // namespace epa::diag
