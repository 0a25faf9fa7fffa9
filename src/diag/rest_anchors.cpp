#include "diag/rest_anchors.hpp"

#include <algorithm>
#include <cmath>

namespace epa::diag {

namespace {

constexpr double kScatterPercentileOfNoise = 0.865;

struct LineFit {
  double slope_mm_s = 0.0;
  double scatter_mm = 0.0;  // RMS distance of the readings from the line
};

// Least-squares line through y[first, first + n) at times k Ts.
LineFit fit_line(const std::vector<double>& y, std::size_t first, std::size_t n, double Ts) {
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * Ts, v = y[first + i];
    st += t, sy += v, stt += t * t, sty += t * v;
  }
  const double dn = static_cast<double>(n), det = dn * stt - st * st;
  const double slope = (dn * sty - st * sy) / det, mean_t = st / dn, mean_y = sy / dn;
  double sse = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double e = y[first + i] - (mean_y + slope * (static_cast<double>(i) * Ts - mean_t));
    sse += e * e;
  }
  return {slope, std::sqrt(sse / dn)};
}

}  // namespace

double reading_noise_mm(const core::Run& run) {
  std::vector<double> scatter;
  for (std::size_t k = 0; k + kRestWindow <= run.size(); k += kRestWindow) scatter.push_back(fit_line(run.y_mm, k, kRestWindow, run.Ts).scatter_mm);
  if (scatter.empty()) return 0.0;
  const auto at = scatter.begin() + static_cast<std::ptrdiff_t>(scatter.size() / 5);
  std::nth_element(scatter.begin(), at, scatter.end());
  // White noise of deviation s scatters about a fitted line by sqrt(chi2(n - 2) / n) s, whose 20th
  // percentile at n = 40 is 0.865 s.
  return *at / kScatterPercentileOfNoise;
}

RestAnchors rest_anchors(const core::Run& run) {
  RestAnchors out;
  out.noise_std_mm = reading_noise_mm(run);
  const double n = static_cast<double>(kRestWindow);
  // The slope's standard error under white noise of that scatter.
  const double slope_se = out.noise_std_mm * std::sqrt(12.0 / (n * (n * n - 1.0))) / run.Ts;
  const double max_slope = std::max(kRestSpeedMmS, 4.0 * slope_se);
  const double max_scatter = 1.5 * out.noise_std_mm + 1e-3;  // + 1 um: a noise-free recording
  // A run that starts with the piston at rest (its first readings flat within the noise) is
  // anchored at its first reading: a step recorded from rest moves before any window could see a rest.
  if (run.size() > kStartReadings) {
    const auto [lo, hi] = std::minmax_element(run.y_mm.begin(), run.y_mm.begin() + kStartReadings);
    if (*hi - *lo <= 4.0 * out.noise_std_mm + 1e-3) out.anchors.push_back({0, run.y_mm.front(), 1});
  }
  std::size_t span_end = 0, span_length = 0;  // the current span of samples at rest (window ending there)
  auto close_span = [&] {
    out.spans.push_back({span_end + 1 - (span_length + kRestWindow - 1), span_end});
    if (span_length + kRestWindow - 1 < kRestWindow + kAnchorMargin) return;
    const std::size_t k = span_end - kAnchorMargin;
    if (!out.anchors.empty() && out.anchors.back().k == 0 && k < kRestWindow) out.anchors.pop_back();  // the same rest
    const std::size_t readings = std::min(kRestWindow, span_length + kRestWindow - 1 - kAnchorMargin);
    double sum = 0;
    for (std::size_t i = 0; i < readings; ++i) sum += run.y_mm[k - i];
    out.anchors.push_back({k, sum / static_cast<double>(readings), readings});
  };
  for (std::size_t k = kRestWindow - 1; k < run.size(); ++k) {
    const LineFit line = fit_line(run.y_mm, k + 1 - kRestWindow, kRestWindow, run.Ts);
    if (std::abs(line.slope_mm_s) <= max_slope && line.scatter_mm <= max_scatter) {
      span_end = k, ++span_length;
      continue;
    }
    if (span_length > 0) close_span();
    span_length = 0;
  }
  if (span_length > 0) close_span();
  return out;
}

}  // namespace epa::diag
