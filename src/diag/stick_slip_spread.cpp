#include "diag/stick_slip_spread.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "diag/axis_change_fit.hpp"

namespace epa::diag {

namespace {

core::Run part_of(const core::Run& run, std::size_t from, std::size_t to) {
  core::Run p;
  p.Ts = run.Ts;
  p.t_s.assign(run.t_s.begin() + static_cast<std::ptrdiff_t>(from), run.t_s.begin() + static_cast<std::ptrdiff_t>(to));
  p.y_mm.assign(run.y_mm.begin() + static_cast<std::ptrdiff_t>(from), run.y_mm.begin() + static_cast<std::ptrdiff_t>(to));
  p.u_V.assign(run.u_V.begin() + static_cast<std::ptrdiff_t>(from), run.u_V.begin() + static_cast<std::ptrdiff_t>(to));
  return p;
}

std::vector<core::Run> parts(std::span<const core::Run* const> runs) {
  std::vector<core::Run> out;
  for (const auto* run : runs) {
    const std::size_t n = run->size(), length = static_cast<std::size_t>(std::lround(kSpreadPartS / run->Ts));
    for (std::size_t from = 0; from < n; from += length) {
      const std::size_t to = n - from < 2 * length ? n : from + length;  // a short tail joins the last part
      out.push_back(part_of(*run, from, to));
      if (to == n) break;
    }
  }
  return out;
}

}  // namespace

core::StickSlipSpread stick_slip_spread(const core::StickSlipParams& params, double Ts, std::span<const core::Run* const> runs,
                                        const JudgedScope& scope) {
  core::StickSlipSpread spread;
  for (const auto& part : parts(runs)) {
    const std::vector<AnchoredRun> one{{&part, rest_anchors(part)}};
    const ChangeFitData data{params, Ts, one, one, scope};
    for (const auto term : kAxisChanges) {
      const ChangeFit fit = fit_change(data, {term});
      const double size = change_size(term, fit.change, params);
      switch (term) {
        case ChangeTerm::kFriction: spread.friction_log_ratio = std::max(spread.friction_log_ratio, size); break;
        case ChangeTerm::kFlowGain: spread.flow_gain_log_ratio = std::max(spread.flow_gain_log_ratio, size); break;
        case ChangeTerm::kDeadBand: spread.break_v = std::max(spread.break_v, size); break;
        case ChangeTerm::kSpoolLag: spread.spool_lag_s = std::max(spread.spool_lag_s, size); break;
        case ChangeTerm::kDeadTime: spread.delay_samples = std::max(spread.delay_samples, size); break;
        case ChangeTerm::kSupply: break;  // held to friction's spread (tolerance_term)
      }
    }
  }
  return spread;
}

}  // namespace epa::diag
