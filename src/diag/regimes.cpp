#include "diag/regimes.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

namespace epa::diag {

namespace {

enum Dim : std::size_t { kMotionValve, kDirection, kValve, kStroke, kMoveSize, kPhase };

const std::array<std::vector<std::string>, kDimensions> kRegimes = {{
    {"rest-near-deadband", "rest-beyond-deadband", "moving-near-deadband", "moving-beyond-deadband"},
    {"rest", "extending", "retracting"},
    {"valve-near-deadband", "valve-beyond-deadband"},
    {"stroke-low", "stroke-middle", "stroke-high"},
    {"rest", "small-move", "large-move"},
    {"transient", "steady"},
}};
constexpr std::array<std::string_view, kDimensions> kDimensionNames = {"motion and valve", "direction", "valve command",
                                                                       "position along the stroke", "move size",
                                                                       "transient or steady"};
constexpr std::size_t kSpeedSpan = 5;  // samples each side of the central difference

double correlation(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = std::min(x.size(), y.size());
  if (n < 3) return 0.0;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= static_cast<double>(n), my /= static_cast<double>(n);
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx), syy += (y[i] - my) * (y[i] - my);
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : 0.0;
}

}  // namespace

std::string_view dimension_name(std::size_t d) { return kDimensionNames[d]; }
const std::vector<std::string>& regime_names(std::size_t d) { return kRegimes[d]; }

SampleLabels label_samples(const core::Run& run, const core::DeadZone& dz, const RegimeOptions& o) {
  const std::size_t n = run.size();
  SampleLabels out;
  out.label.resize(n);
  std::vector<int> direction(n, 0);  // 0 rest, 1 extending, 2 retracting
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t lo = k >= kSpeedSpan ? k - kSpeedSpan : 0, hi = std::min(n - 1, k + kSpeedSpan);
    const double speed = hi > lo ? (run.y_mm[hi] - run.y_mm[lo]) / (static_cast<double>(hi - lo) * run.Ts) : 0.0;
    direction[k] = std::abs(speed) <= o.moving_mm_s ? 0 : speed > 0 ? 1 : 2;
  }
  // Moves: maximal stretches of motion, sized by their travel.
  std::vector<int> move(n, 0);
  for (std::size_t k = 0; k < n;) {
    if (direction[k] == 0) { ++k; continue; }
    std::size_t e = k;
    while (e < n && direction[e] != 0) ++e;
    const int size = std::abs(run.y_mm[e - 1] - run.y_mm[k]) < o.small_move_mm ? 1 : 2;
    std::fill(move.begin() + static_cast<std::ptrdiff_t>(k), move.begin() + static_cast<std::ptrdiff_t>(e), size);
    k = e;
  }
  const auto transient_samples = static_cast<std::size_t>(std::llround(o.transient_s / run.Ts));
  std::size_t since_event = transient_samples;
  for (std::size_t k = 0; k < n; ++k) {
    const bool event = k > 0 && ((direction[k] == 0) != (direction[k - 1] == 0) || std::abs(run.u_V[k] - run.u_V[k - 1]) > o.valve_step_V);
    since_event = event ? 0 : since_event + 1;
    const bool near = run.u_V[k] >= dz.b_l - o.deadband_margin_V && run.u_V[k] <= dz.b_r + o.deadband_margin_V;
    const bool moving = direction[k] != 0;
    auto& l = out.label[k];
    l[kMotionValve] = static_cast<std::uint8_t>((moving ? 2 : 0) + (near ? 0 : 1));
    l[kDirection] = static_cast<std::uint8_t>(direction[k]);
    l[kValve] = near ? 0 : 1;
    const double third = o.stroke_mm / 3.0;
    l[kStroke] = static_cast<std::uint8_t>(run.y_mm[k] < third ? 0 : run.y_mm[k] < 2 * third ? 1 : 2);
    l[kMoveSize] = static_cast<std::uint8_t>(move[k]);
    l[kPhase] = since_event < transient_samples ? 0 : 1;
  }
  return out;
}

RegimeSums::RegimeSums() {
  for (std::size_t d = 0; d < kDimensions; ++d) sums[d].resize(kRegimes[d].size());
}

void RegimeSums::add(const WindowedReplay& r, const SampleLabels& labels) {
  for (std::size_t i = 0; i < r.k.size(); ++i) {
    const auto& l = labels.label[r.k[i]];
    const double e2 = r.error_mm[i] * r.error_mm[i];
    for (std::size_t d = 0; d < kDimensions; ++d) sums[d][l[d]].sse_mm2 += e2, ++sums[d][l[d]].n;
  }
}

std::vector<RegimeShare> shares(const RegimeSums& s) {
  std::vector<RegimeShare> out;
  for (std::size_t d = 0; d < kDimensions; ++d) {
    GapSum total;
    for (const auto& g : s.sums[d]) total += g;
    for (std::size_t r = 0; r < s.sums[d].size(); ++r) {
      const auto& g = s.sums[d][r];
      if (g.n == 0) continue;
      out.push_back({std::string(kDimensionNames[d]), kRegimes[d][r],
                     total.n ? 100.0 * static_cast<double>(g.n) / static_cast<double>(total.n) : 0.0,
                     total.sse_mm2 > 0 ? 100.0 * g.sse_mm2 / total.sse_mm2 : 0.0, g.rms_mm()});
    }
  }
  return out;
}

ResidualStats residual_stats(const std::vector<const core::Run*>& runs, const std::vector<WindowedReplay>& replays,
                             std::size_t max_lag) {
  ResidualStats st;
  st.autocorrelation.assign(max_lag, 0.0);
  st.input_crosscorrelation.assign(max_lag + 1, 0.0);
  for (std::size_t lag = 0; lag <= max_lag; ++lag) {
    std::vector<double> e, e_lag, du;
    for (std::size_t r = 0; r < runs.size() && r < replays.size(); ++r) {
      const auto& rep = replays[r];
      const auto& u = runs[r]->u_V;
      for (std::size_t i = 0; i < rep.k.size(); ++i) {
        const std::size_t k = rep.k[i];
        if (lag >= 1 && i >= lag && rep.k[i - lag] + lag == k) e.push_back(rep.error_mm[i]), e_lag.push_back(rep.error_mm[i - lag]);
        // u(k-1) was the command that moved the piston to k; a delay shows as a later peak.
        if (k >= lag + 2) du.push_back(u[k - 1 - lag] - u[k - 2 - lag]);
        else du.push_back(0.0);
      }
    }
    if (lag >= 1) st.autocorrelation[lag - 1] = correlation(e, e_lag);
    std::vector<double> all_e;
    for (const auto& rep : replays) all_e.insert(all_e.end(), rep.error_mm.begin(), rep.error_mm.end());
    st.input_crosscorrelation[lag] = correlation(all_e, du);
    if (std::abs(st.input_crosscorrelation[lag]) > std::abs(st.peak_input_correlation))
      st.peak_input_correlation = st.input_crosscorrelation[lag], st.peak_input_lag = lag;
  }
  return st;
}

std::vector<std::string> hints(const std::vector<RegimeShare>& sh, const ResidualStats& st) {
  std::vector<std::string> out;
  for (const auto& s : sh) {
    if (s.time_share_pct < 5.0 || s.gap_share_pct < 1.5 * s.time_share_pct) continue;
    std::string h = fmt::format("{}: {:.0f} % of the gap in {:.0f} % of the time", s.regime, s.gap_share_pct, s.time_share_pct);
    if (s.regime.find("near-deadband") != std::string::npos) h += " (break points or friction)";
    else if (s.regime == "large-move" || s.regime == "moving-beyond-deadband") h += " (gain, flow saturation)";
    else if (s.regime.rfind("stroke-", 0) == 0) h += " (dynamics that change along the stroke)";
    else if (s.regime == "transient") h += " (delay, valve lag, friction)";
    out.push_back(h);
  }
  if (std::abs(st.peak_input_correlation) > 0.2)
    out.push_back(fmt::format("the error follows valve command changes {} sample(s) earlier (r = {:.2f}): timing (delay, lag)",
                              st.peak_input_lag, st.peak_input_correlation));
  return out;
}

}  // namespace epa::diag
