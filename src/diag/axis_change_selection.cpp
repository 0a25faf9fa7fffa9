#include "diag/axis_change_selection.hpp"

#include <algorithm>

#include "diag/whole_move.hpp"

namespace epa::diag {

namespace {

double reduction_pct(double before_mm, double after_mm, double base_mm) {
  return base_mm > 0 ? 100.0 * (before_mm - after_mm) / base_mm : 0.0;
}

// The first round of the forward selection is the candidates' own fits, each change alone.
const ChangeFit& alone(const std::vector<ChangeCandidate>& candidates, ChangeTerm term) {
  return std::find_if(candidates.begin(), candidates.end(), [&](const ChangeCandidate& c) { return c.term == term; })->fit;
}

std::vector<ChangeTerm> with(std::vector<ChangeTerm> terms, ChangeTerm term) {
  terms.push_back(term);
  return terms;
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
  for (const ChangeTerm term : kAxisChanges) {
    ChangeCandidate c{term, fit_change(data, {term})};
    c.reduction_pct = reduction_pct(base, c.fit.heldout_gap_mm, base);
    c.beyond_tolerance = beyond_tolerance(term, c.fit.change, data.commissioned, tolerance);
    out.evaluations += c.fit.evaluations;
    out.candidates.push_back(c);
  }
  std::sort(out.candidates.begin(), out.candidates.end(), [](const auto& a, const auto& b) { return a.reduction_pct > b.reduction_pct; });

  double current = base;
  while (out.judged && out.accepted.terms.size() < kMaxChanges && current > kSignificantOverFloor * noise_floor_mm) {
    std::optional<ChangeFit> best;
    for (const ChangeTerm term : kAxisChanges) {
      if (out.accepted.has(term)) continue;
      ChangeFit fit = out.accepted.terms.empty() ? alone(out.candidates, term) : fit_change(data, with(out.accepted.terms, term), out.accepted);
      if (!out.accepted.terms.empty()) out.evaluations += fit.evaluations;
      if (!beyond_tolerance(term, fit.change, data.commissioned, tolerance)) continue;
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
