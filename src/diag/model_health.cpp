#include "diag/model_health.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/format.hpp"
#include "diag/axis_change_fit.hpp"

namespace epa::diag {

namespace {

using plant::EffectKind;

// The baseline is fitted on the continuous terms at once; the dead time stays the commissioned
// one (searching it whole would multiply the fit's cost by kMaxDelay + 1), and the supply out of
// it (fitted beside the flow gain on an unchanged axis it moved the spring x1.6-2.3).
const std::vector<ChangeTerm> kBaselineTerms = {ChangeTerm::kFriction, ChangeTerm::kFlowGain, ChangeTerm::kDeadBand,
                                                ChangeTerm::kSpoolLag};

// Every term a window is re-fitted in, one at a time.
constexpr ChangeTerm kMonitoredTerms[] = {ChangeTerm::kFriction, ChangeTerm::kFlowGain, ChangeTerm::kSupply,
                                          ChangeTerm::kDeadBand, ChangeTerm::kSpoolLag, ChangeTerm::kDeadTime};

// The moves one after the other as one run, so that the model carries what a move leaves in it
// (the air spring's wind-up above all, which sets when the next breakaway comes) into the next,
// as the axis does: between moves the valve rests in its dead band and the piston stands.
core::Run joined(const std::deque<core::Run>& moves) {
  core::Run out;
  out.Ts = moves.empty() ? 0.005 : moves.front().Ts;
  for (const auto& m : moves) {
    const double t0 = out.t_s.empty() ? 0.0 : out.t_s.back() + out.Ts;
    for (std::size_t k = 0; k < m.size(); ++k) {
      out.t_s.push_back(t0 + m.t_s[k] - m.t_s.front());
      out.y_mm.push_back(m.y_mm[k]);
      out.u_V.push_back(m.u_V[k]);
    }
  }
  return out;
}

// The joined run's rests, less those in its first `warm_up` samples: the model runs through the
// window's first move unjudged, so that its wind-up, unknown at the window's start (a free run
// starts with the spring unwound, the axis with whatever the last move left), is its own by then.
std::vector<AnchoredRun> anchored(const core::Run& run, std::size_t warm_up) {
  const core::Run* runs[] = {&run};
  auto out = anchor_runs(runs);
  auto& anchors = out.front().rests.anchors;
  anchors.erase(anchors.begin(), std::find_if(anchors.begin(), anchors.end(), [&](const RestAnchor& a) { return a.k >= warm_up; }));
  return out;
}

// Adds a term's estimate as its effect's, or in place of the effect's other term when it explains more.
void add_estimate(std::vector<EffectEstimate>& estimates, const EffectEstimate& e) {
  const auto same = std::find_if(estimates.begin(), estimates.end(), [&](const EffectEstimate& o) { return o.effect == e.effect; });
  if (same == estimates.end()) estimates.push_back(e);
  else if (e.reduction > same->reduction) *same = e;
}

std::size_t judged_segments(const core::StickSlipParams& model, double Ts, const std::vector<AnchoredRun>& runs, const JudgedScope& scope) {
  std::size_t n = 0;
  for (const auto& r : runs) n += from_rest_sse(model, Ts, r, scope).windows;
  return n;
}

// The term an effect changes, in its unit.
struct Term {
  double value;
  const char* unit;
};
Term term_of(ChangeTerm term, const core::StickSlipParams& p) {
  switch (term) {
    case ChangeTerm::kFriction: return {p.static_mm, "mm"};
    case ChangeTerm::kFlowGain: return {p.speed_right_mm_s_per_v, "mm/s/V"};
    case ChangeTerm::kSupply: return {p.spring_rad_s, "rad/s"};
    case ChangeTerm::kDeadBand: return {p.break_right_v, "V"};
    case ChangeTerm::kSpoolLag: return {p.spool_lag_s, "s"};
    case ChangeTerm::kDeadTime: return {static_cast<double>(p.delay_samples), "samples"};
  }
  return {0.0, ""};
}

// The term's quantity in words, with its value: "breakaway wind-up 5.77 mm".
std::string term_words(ChangeTerm term, const core::StickSlipParams& p) {
  char text[64];
  switch (term) {
    case ChangeTerm::kFriction: std::snprintf(text, sizeof text, "breakaway wind-up %.3g mm", p.static_mm); break;
    case ChangeTerm::kFlowGain: std::snprintf(text, sizeof text, "speed %.3g mm/s per V", p.speed_right_mm_s_per_v); break;
    case ChangeTerm::kSupply: std::snprintf(text, sizeof text, "air spring %.3g rad/s", p.spring_rad_s); break;
    case ChangeTerm::kDeadBand: std::snprintf(text, sizeof text, "right break point %.3g V", p.break_right_v); break;
    case ChangeTerm::kSpoolLag: std::snprintf(text, sizeof text, "lag %.3g ms", p.spool_lag_s * 1e3); break;
    case ChangeTerm::kDeadTime: std::snprintf(text, sizeof text, "dead time %d samples", p.delay_samples); break;
  }
  return text;
}

// The smallest change of `term` ever named, in change_size's units (axis_change.hpp). The supply
// takes friction's (tolerance_term): with the flow gain's floor it named windows of an unchanged
// axis whose friction scattered.
double floor_of(const HealthConfig& c, ChangeTerm term) {
  switch (tolerance_term(term)) {
    case ChangeTerm::kFriction: return std::log1p(c.friction_ratio_tolerance);
    case ChangeTerm::kFlowGain: return std::log1p(c.gain_ratio_tolerance);
    case ChangeTerm::kDeadBand: return c.break_tolerance_v;
    case ChangeTerm::kSpoolLag: return c.lag_tolerance_s;
    case ChangeTerm::kDeadTime: return 1.0;
    case ChangeTerm::kSupply: break;  // held to friction's
  }
  return 0.0;
}

}  // namespace

const char* to_string(HealthState state) {
  switch (state) {
    case HealthState::kOff: return "off";
    case HealthState::kLearning: return "learning";
    case HealthState::kOk: return "ok";
    case HealthState::kDrifting: return "drifting";
    case HealthState::kUnexplained: return "unexplained";
    case HealthState::kHunting: return "hunting";
  }
  return "?";
}

std::string HealthConfig::problem() const {
  if (baseline_moves < 2 || baseline_moves > 100) return "baseline_moves must lie in 2..100";
  if (window_moves < 2 || window_moves > 100) return "window_moves must lie in 2..100";
  if (baseline_moves < window_moves) return "baseline_moves must be at least window_moves";
  if (!(spread_margin >= 1.0 && spread_margin <= 10.0)) return "spread_margin must lie in [1, 10]";
  if (confirm_windows < 1 || confirm_windows > 20) return "confirm_windows must lie in 1..20";
  if (!(min_reduction > 0.0 && min_reduction < 1.0)) return "min_reduction must lie in (0, 1)";
  if (!(unexplained_gap_ratio > 1.0 && unexplained_gap_ratio <= 100.0)) return "unexplained_gap_ratio must lie in (1, 100]";
  if (!(friction_ratio_tolerance > 0.0 && friction_ratio_tolerance <= 10.0)) return "friction_ratio_tolerance must lie in (0, 10]";
  if (!(gain_ratio_tolerance > 0.0 && gain_ratio_tolerance <= 10.0)) return "gain_ratio_tolerance must lie in (0, 10]";
  if (!(break_tolerance_v > 0.0 && break_tolerance_v <= 5.0)) return "break_tolerance_v must lie in (0, 5]";
  if (!(lag_tolerance_s > 0.0 && lag_tolerance_s <= 1.0)) return "lag_tolerance_s must lie in (0, 1]";
  return "";
}

core::Result<ModelHealth> ModelHealth::make(const core::StickSlipParams& commissioned, double Ts, double stroke_mm, HealthConfig config,
                                            std::optional<std::array<double, 2>> drive_range_v) {
  if (auto s = commissioned.validate(); !s) return core::invalid_argument("model health: the commissioned model: " + s.error().message);
  if (!(Ts > 0.0) || !std::isfinite(Ts)) return core::invalid_argument("model health: Ts must be > 0");
  if (!(stroke_mm > 0.0) || !std::isfinite(stroke_mm)) return core::invalid_argument("model health: the stroke must be > 0 mm");
  if (const auto p = config.problem(); !p.empty()) return core::invalid_argument("model health: " + p);
  return ModelHealth(commissioned, Ts, stroke_mm, config, drive_range_v);
}

ModelHealth::ModelHealth(const core::StickSlipParams& commissioned, double Ts, double stroke_mm, HealthConfig config,
                         std::optional<std::array<double, 2>> drive_range_v)
    : commissioned_(commissioned), baseline_(commissioned), Ts_(Ts), config_(config) {
  scope_.stroke_mm = stroke_mm;
  scope_.span_s = config.span_s;
  if (drive_range_v) scope_.drive_lo_v = (*drive_range_v)[0], scope_.drive_hi_v = (*drive_range_v)[1];
  verdict_.state = HealthState::kLearning;
}

void ModelHealth::retake_baseline() {
  moves_.clear();
  have_baseline_ = false;
  baseline_ = commissioned_;
  candidate_.reset();
  agreeing_ = 0;
  verdict_ = HealthVerdict{};
  verdict_.state = HealthState::kLearning;
}

std::string drift_words(ChangeTerm term, const core::StickSlipParams& baseline, const core::StickSlipParams& now,
                        const core::StickSlipParams& commissioned) {
  return describe_change(term, change_between(term, baseline, now), baseline) + " since the baseline (" + term_words(term, now) +
         " now, " + term_words(term, commissioned) + " as commissioned)";
}

WindowReading read_window(const std::vector<EffectEstimate>& per_term, double gap_mm, double unchanged_gap_mm, double baseline_gap_mm,
                          const HealthConfig& config) {
  std::optional<std::size_t> best;     // the change beyond tolerance that explains most
  double best_within_tolerance = 0.0;  // the most any change within it explains
  for (std::size_t i = 0; i < per_term.size(); ++i) {
    const EffectEstimate& e = per_term[i];
    if (!e.beyond_tolerance) best_within_tolerance = std::max(best_within_tolerance, e.reduction);
    else if (!best || e.reduction > per_term[*best].reduction) best = i;
  }
  // A window no wider than the unchanged axis's own is not a drift, however well a change fits it:
  // on an unchanged axis a single term re-fitted to a window's moves shrank its gap by up to 65 %.
  // Nor is one that a change within the unchanged axis's scatter explains better: with the supply
  // among the terms, windows of an unchanged axis were named for a term that explained a third of
  // their gap while friction within its tolerance explained two thirds.
  if (best && per_term[*best].reduction >= config.min_reduction && per_term[*best].reduction >= best_within_tolerance &&
      gap_mm > unchanged_gap_mm)
    return {HealthState::kDrifting, best};
  if (gap_mm > config.unexplained_gap_ratio * baseline_gap_mm) return {HealthState::kUnexplained, std::nullopt};
  return {};
}

bool ModelHealth::add_move(core::Run run, bool hunted) {
  const HealthState state_before = verdict_.state;
  const auto effect_before = verdict_.effect;
  ++verdict_.moves_seen;
  moves_.push_back(std::move(run));
  if (!have_baseline_) {
    if (moves_.size() >= config_.baseline_moves) {
      fit_baseline();
      moves_.clear();
      verdict_.state = HealthState::kOk;
    }
  } else {
    while (moves_.size() > config_.window_moves) moves_.pop_front();
    if (moves_.size() == config_.window_moves) judge();
  }
  if (hunted) verdict_.state = HealthState::kHunting;  // until a judgement without it
  return verdict_.state != state_before || verdict_.effect != effect_before;
}

void ModelHealth::fit_baseline() {
  const core::Run run = joined(moves_);
  const auto runs = anchored(run, moves_.front().size());
  const ChangeFitData data{commissioned_, Ts_, runs, runs, scope_};
  const ChangeFit joint = fit_change(data, kBaselineTerms);
  fits_ += joint.evaluations;
  baseline_ = apply_change(commissioned_, joint.change);
  verdict_.baseline_gap_mm = from_rest_gap_mm(baseline_, Ts_, runs, scope_);
  have_baseline_ = true;
  // How far windows of the unchanged axis scatter about the baseline: each effect fitted on the
  // baseline's own windows, half a window apart. A later change is named only beyond
  // spread_margin times the widest of them (and beyond the floor).
  for (const ChangeTerm term : kMonitoredTerms) tolerance_[index(term)] = floor_of(config_, term);
  unchanged_gap_mm_ = verdict_.baseline_gap_mm;
  const std::deque<core::Run> all = moves_;
  for (std::size_t first = 0; first + config_.window_moves <= all.size(); first += std::max<std::size_t>(1, config_.window_moves / 2)) {
    moves_.assign(all.begin() + static_cast<std::ptrdiff_t>(first), all.begin() + static_cast<std::ptrdiff_t>(first + config_.window_moves));
    const core::Run window = joined(moves_);
    const auto window_runs = anchored(window, moves_.front().size());
    const ChangeFitData window_data{baseline_, Ts_, window_runs, window_runs, scope_};
    unchanged_gap_mm_ = std::max(unchanged_gap_mm_, from_rest_gap_mm(baseline_, Ts_, window_runs, scope_));
    for (const ChangeTerm term : kMonitoredTerms) {
      const ChangeFit fit = fit_change(window_data, {term});
      fits_ += fit.evaluations;
      double& t = tolerance_[index(term)];
      t = std::max(t, config_.spread_margin * change_size(term, fit.change, baseline_));
    }
  }
  moves_ = all;
}

std::size_t ModelHealth::first_move_explained(const core::StickSlipParams& changed, const core::Run& run) const {
  const auto runs = anchored(run, moves_.front().size());
  const FreeRunTrace before = from_rest_trace(baseline_, Ts_, runs.front(), scope_);
  const FreeRunTrace after = from_rest_trace(changed, Ts_, runs.front(), scope_);
  std::vector<double> sse_before(moves_.size()), sse_after(moves_.size());
  std::vector<std::size_t> move_end;  // the first sample of the next move
  for (std::size_t i = 0, end = 0; i < moves_.size(); ++i) move_end.push_back(end += moves_[i].size());
  const auto add = [&](const FreeRunTrace& t, std::vector<double>& sse) {
    for (std::size_t i = 0; i < t.k.size(); ++i) {
      const std::size_t m = std::upper_bound(move_end.begin(), move_end.end(), t.k[i]) - move_end.begin();
      const double e = t.predicted_mm[i] - run.y_mm[t.k[i]];
      if (m < sse.size()) sse[m] += e * e;
    }
  };
  add(before, sse_before);
  add(after, sse_after);
  for (std::size_t m = 0; m < moves_.size(); ++m)
    if (sse_after[m] < sse_before[m]) return m;
  return moves_.size() - 1;
}

void ModelHealth::judge() {
  const core::Run run = joined(moves_);
  const auto runs = anchored(run, moves_.front().size());
  if (judged_segments(baseline_, Ts_, runs, scope_) < config_.min_judged_segments) return;  // nothing to judge on
  const double gap_mm = from_rest_gap_mm(baseline_, Ts_, runs, scope_);
  verdict_.window_gap_mm = gap_mm;
  const ChangeFitData data{baseline_, Ts_, runs, runs, scope_};

  verdict_.estimates.clear();
  std::vector<EffectEstimate> per_term;
  std::vector<core::StickSlipParams> changed_models;
  for (const ChangeTerm term : kMonitoredTerms) {
    const ChangeFit fit = fit_change(data, {term});
    fits_ += fit.evaluations;
    const core::StickSlipParams changed = apply_change(baseline_, fit.change);
    EffectEstimate e;
    e.effect = effect_of(term);
    e.term = term;
    e.value = term_of(term, changed).value;
    e.commissioned = term_of(term, commissioned_).value;
    e.ratio = e.commissioned != 0.0 ? e.value / e.commissioned : 1.0;
    e.reduction = gap_mm > 0.0 ? std::max(0.0, (gap_mm - fit.train_gap_mm) / gap_mm) : 0.0;
    e.beyond_tolerance = change_size(term, fit.change, baseline_) > tolerance_[index(term)];
    add_estimate(verdict_.estimates, e);
    per_term.push_back(e);
    changed_models.push_back(changed);
  }

  // This judgement's reading, then whether enough judgements in a row agree on it.
  const WindowReading window = read_window(per_term, gap_mm, unchanged_gap_mm_, verdict_.baseline_gap_mm, config_);
  const HealthState reading = window.state;
  const std::optional<EffectEstimate> best = window.named ? std::optional(per_term[*window.named]) : std::nullopt;
  const core::StickSlipParams& best_model = window.named ? changed_models[*window.named] : baseline_;
  const std::optional<EffectKind> effect = best ? std::optional(best->effect) : std::nullopt;
  if (reading == candidate_state_ && effect == candidate_) {
    ++agreeing_;
  } else {
    candidate_state_ = reading;
    candidate_ = effect;
    agreeing_ = 1;
    // The onset: the oldest move of this window that the reading explains better than the baseline.
    std::size_t first = 0;
    if (reading == HealthState::kDrifting) first = first_move_explained(best_model, run);
    onset_move_ = verdict_.moves_seen - moves_.size() + first + 1;
  }
  if (agreeing_ < config_.confirm_windows && verdict_.state != HealthState::kHunting) return;

  verdict_.state = reading;
  verdict_.effect = effect;
  verdict_.moves_since_onset = reading == HealthState::kOk ? 0 : verdict_.moves_seen - onset_move_ + 1;
  if (effect) {
    const Term t = term_of(best->term, best_model);
    verdict_.value = t.value;
    verdict_.unit = t.unit;
    verdict_.commissioned = term_of(best->term, commissioned_).value;
    verdict_.ratio = verdict_.commissioned != 0.0 ? verdict_.value / verdict_.commissioned : 1.0;
    verdict_.size = drift_words(best->term, baseline_, best_model, commissioned_);
  } else {
    verdict_.value = verdict_.commissioned = 0.0;
    verdict_.ratio = 1.0;
    verdict_.unit.clear();
    verdict_.size.clear();
  }
}

}  // namespace epa::diag
