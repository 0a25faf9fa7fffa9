#include "diag/axis_change_selection.hpp"

#include <algorithm>

#include "diag/whole_move.hpp"

namespace epa::diag {

namespace {

using plant::EffectKind;

double reduction_pct(double before_mm, double after_mm, double base_mm) {
  return base_mm > 0 ? 100.0 * (before_mm - after_mm) / base_mm : 0.0;
}

// The first round of the forward selection is the candidates' own fits, each change alone.
const ChangeFit& alone(const std::vector<ChangeCandidate>& candidates, EffectKind kind) {
  return std::find_if(candidates.begin(), candidates.end(), [&](const ChangeCandidate& c) { return c.effect == kind; })->fit;
}

std::vector<EffectKind> with(std::vector<EffectKind> kinds, EffectKind kind) {
  kinds.push_back(kind);
  return kinds;
}

}  // namespace

AxisChanges select_axis_changes(const ChangeFitData& data, const std::optional<core::StickSlipSpread>& spread, double noise_floor_mm,
                                bool rest_drift_significant) {
  AxisChanges out;
  out.judged = spread.has_value();
  const core::StickSlipSpread tolerance = spread.value_or(core::StickSlipSpread{});
  out.commissioned_train_mm = from_rest_gap_mm(data.commissioned, data.Ts, data.train, data.scope);
  out.commissioned_heldout_mm = from_rest_gap_mm(data.commissioned, data.Ts, data.heldout, data.scope);
  const double base = out.commissioned_heldout_mm;
  for (const EffectKind kind : kAxisChanges) {
    ChangeCandidate c{kind, fit_change(data, {kind})};
    c.reduction_pct = reduction_pct(base, c.fit.heldout_gap_mm, base);
    c.beyond_tolerance = beyond_tolerance(kind, c.fit.change, data.commissioned, tolerance);
    out.evaluations += c.fit.evaluations;
    out.candidates.push_back(c);
  }
  std::sort(out.candidates.begin(), out.candidates.end(), [](const auto& a, const auto& b) { return a.reduction_pct > b.reduction_pct; });

  double current = base;
  while (out.judged && out.accepted.kinds.size() < kMaxChanges && current > kSignificantOverFloor * noise_floor_mm) {
    std::optional<ChangeFit> best;
    for (const EffectKind kind : kAxisChanges) {
      if (out.accepted.has(kind)) continue;
      ChangeFit fit = out.accepted.kinds.empty() ? alone(out.candidates, kind) : fit_change(data, with(out.accepted.kinds, kind), out.accepted);
      if (!out.accepted.kinds.empty()) out.evaluations += fit.evaluations;
      if (!beyond_tolerance(kind, fit.change, data.commissioned, tolerance)) continue;
      if (!best || fit.heldout_gap_mm < best->heldout_gap_mm) best = fit;
    }
    if (!best || reduction_pct(current, best->heldout_gap_mm, base) < kChangeThresholdPct) break;
    out.accepted = best->change;
    current = best->heldout_gap_mm;
  }
  out.heldout_after_mm = current;
  out.reduction_pct = reduction_pct(base, current, base);
  out.unexplained = rest_drift_significant;  // whatever else changed, no change of the model's terms does that
  return out;
}

}  // namespace epa::diag
