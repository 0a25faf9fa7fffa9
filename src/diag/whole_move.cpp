#include "diag/whole_move.hpp"

#include <algorithm>
#include <cmath>

namespace epa::diag {

namespace {

using plant::EffectKind;

constexpr double kTraceS = 20.0;

core::StickSlipParams without(EffectKind term, core::StickSlipParams p) {
  switch (term) {
    case EffectKind::kStaticFriction: p.coulomb_mm = p.static_mm = 0.0; break;
    case EffectKind::kValveLag: p.spool_lag_s = 0.0; break;
    case EffectKind::kInputDelay: p.delay_samples = 0; break;
    default: break;
  }
  return p;
}

bool present(EffectKind term, const core::StickSlipParams& p) {
  switch (term) {
    case EffectKind::kStaticFriction: return p.static_mm > 0.0;
    case EffectKind::kValveLag: return p.spool_lag_s > 0.0;
    case EffectKind::kInputDelay: return p.delay_samples > 0;
    default: return false;
  }
}

// Both models' gaps on one run. Each run is run once per model: the pooled gaps, the per-run
// rows and the trace's choice all come from these.
struct RunSums {
  GapSum law, stick_slip;
};

std::vector<RunSums> run_sums(const WholeMoveGap& g, const core::ModelFile& file, std::span<const AnchoredRun> runs) {
  std::vector<RunSums> out;
  for (const auto& r : runs)
    out.push_back({from_rest_sse(file.model, r, g.scope), g.has_stick_slip ? from_rest_sse(g.stick_slip, file.model.Ts, r, g.scope) : GapSum{}});
  return out;
}

GapSum pooled(const std::vector<RunSums>& sums, GapSum RunSums::*model) {
  GapSum s;
  for (const auto& r : sums) s += r.*model;
  return s;
}

void add_per_run(WholeMoveGap& g, const std::vector<RunSums>& sums, const char* set) {
  for (std::size_t i = 0; i < sums.size(); ++i)
    g.per_run.push_back({set, i, sums[i].law.rms_mm(), sums[i].stick_slip.rms_mm(), sums[i].law.windows, sums[i].law.windows_at_end_stop});
}

// The scored run with the most judged readings, from its first judged segment for kTraceS at most.
WholeMoveTrace trace_of(const WholeMoveGap& g, const core::ModelFile& file, std::span<const AnchoredRun> scored,
                        const std::vector<RunSums>& sums, const char* set) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < sums.size(); ++i)
    if (sums[i].law.n > sums[best].law.n) best = i;
  const AnchoredRun& r = scored[best];
  const core::Run& run = *r.run;
  WholeMoveTrace t{set, best, run.t_s, run.y_mm, {}, {}, {}, {}};
  const std::size_t n = run.size();
  t.law_model_mm.assign(n, NAN), t.stick_slip_mm.assign(n, NAN), t.model_stuck.assign(n, NAN), t.recorded_rest.assign(n, 0.0);
  const auto law = from_rest_trace(file.model, r, g.scope);
  for (std::size_t i = 0; i < law.k.size(); ++i) t.law_model_mm[law.k[i]] = law.predicted_mm[i];
  if (g.has_stick_slip) {
    const auto ss = from_rest_trace(g.stick_slip, file.model.Ts, r, g.scope);
    for (std::size_t i = 0; i < ss.k.size(); ++i) t.stick_slip_mm[ss.k[i]] = ss.predicted_mm[i], t.model_stuck[ss.k[i]] = ss.stuck[i] ? 1.0 : 0.0;
  }
  for (const auto& span : r.rests.spans)
    for (std::size_t k = span.first; k <= span.last && k < n; ++k) t.recorded_rest[k] = 1.0;
  // Only kTraceS from the first judged reading: a 90 s run would be a smear.
  const auto first = std::find_if(t.law_model_mm.begin(), t.law_model_mm.end(), [](double v) { return std::isfinite(v); });
  const std::size_t from = first == t.law_model_mm.end() ? 0 : static_cast<std::size_t>(first - t.law_model_mm.begin()) - 1;
  const std::size_t to = std::min(n, from + static_cast<std::size_t>(std::lround(kTraceS / run.Ts)));
  for (auto* v : {&t.t_s, &t.measured_mm, &t.law_model_mm, &t.stick_slip_mm, &t.recorded_rest, &t.model_stuck})
    *v = std::vector<double>(v->begin() + static_cast<std::ptrdiff_t>(from), v->begin() + static_cast<std::ptrdiff_t>(to));
  return t;
}

// Which terms of the stick-slip model the gap needs, each switched off with the rest as the file has it.
void judge_terms(WholeMoveGap& g, const core::ModelFile& file, std::span<const AnchoredRun> scored) {
  const double law_gap = g.hammerstein_heldout.rms_mm(), model_gap = g.stick_slip_heldout.rms_mm();
  for (const EffectKind term : {EffectKind::kStaticFriction, EffectKind::kValveLag, EffectKind::kInputDelay}) {
    if (!present(term, g.stick_slip)) continue;
    MechanicsTerm t{term};
    t.heldout_without_mm = from_rest_gap_mm(without(term, g.stick_slip), file.model.Ts, scored, g.scope);
    t.cost_pct = law_gap > 0 ? 100.0 * (t.heldout_without_mm - model_gap) / law_gap : 0.0;
    g.terms.push_back(t);
  }
  const bool significant = law_gap > kSignificantOverFloor * g.noise_floor_mm && g.explained_pct >= kMechanicsThresholdPct;
  for (auto& t : g.terms) {
    t.named = significant && t.cost_pct >= kMechanicsThresholdPct;
    if (t.named) g.named.push_back(t.effect);
  }
}

}  // namespace

JudgedScope judged_scope(const core::ModelFile& file, double stroke_mm) {
  JudgedScope scope{stroke_mm};
  if (file.identified_drive_v) scope.drive_lo_v = (*file.identified_drive_v)[0], scope.drive_hi_v = (*file.identified_drive_v)[1];
  return scope;
}

double breakaway_m_s2(const core::StickSlipParams& p) { return p.static_mm * p.spring_rad_s * p.spring_rad_s * 1e-3; }
double sliding_m_s2(const core::StickSlipParams& p) { return p.coulomb_mm * p.spring_rad_s * p.spring_rad_s * 1e-3; }

WholeMoveGap whole_move_gap(const core::ModelFile& file, std::span<const AnchoredRun> train_runs, std::span<const AnchoredRun> heldout_runs,
                            const JudgedScope& scope, double noise_std_mm) {
  WholeMoveGap g;
  g.scope = scope;
  g.scoped_to_identified_drive = file.identified_drive_v.has_value();
  const std::span<const AnchoredRun> scored = heldout_runs.empty() ? train_runs : heldout_runs;
  g.noise_floor_mm = from_rest_noise_floor_mm(scored, noise_std_mm);
  g.has_stick_slip = file.stick_slip.has_value();
  if (g.has_stick_slip) g.stick_slip = *file.stick_slip;
  const auto train_sums = run_sums(g, file, train_runs), heldout_sums = run_sums(g, file, heldout_runs);
  const auto& scored_sums = heldout_runs.empty() ? train_sums : heldout_sums;
  g.hammerstein_train = pooled(train_sums, &RunSums::law);
  g.hammerstein_heldout = pooled(scored_sums, &RunSums::law);
  g.segments = g.hammerstein_heldout.windows, g.segments_left_out = g.hammerstein_heldout.windows_at_end_stop;
  if (g.has_stick_slip) {
    g.stick_slip_train = pooled(train_sums, &RunSums::stick_slip);
    g.stick_slip_heldout = pooled(scored_sums, &RunSums::stick_slip);
    const double law_gap = g.hammerstein_heldout.rms_mm();
    g.explained_pct = law_gap > 0 ? 100.0 * (1.0 - g.stick_slip_heldout.rms_mm() / law_gap) : 0.0;
    judge_terms(g, file, scored);
  }
  const double left = g.has_stick_slip ? g.stick_slip_heldout.rms_mm() : g.hammerstein_heldout.rms_mm();
  const bool above_floor = left > kSignificantOverFloor * g.noise_floor_mm;
  g.unexplained = g.named.empty() ? above_floor : above_floor && left > g.hammerstein_heldout.rms_mm() / 3.0;
  add_per_run(g, train_sums, "train");
  if (!heldout_runs.empty()) add_per_run(g, heldout_sums, "heldout");
  if (!scored.empty()) g.trace = trace_of(g, file, scored, scored_sums, heldout_runs.empty() ? "train" : "heldout");
  return g;
}

}  // namespace epa::diag
