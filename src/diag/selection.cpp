#include "diag/selection.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <future>
#include <optional>

#include "diag/chance_threshold.hpp"
#include "diag/sensor_resolution.hpp"

namespace epa::diag {

namespace {

using plant::EffectKind;

struct Models {
  std::vector<ReplayModel> per_fold;  // fitted on each fold's training runs
  ReplayModel all;                    // fitted on all training runs (the reported parameters)
};

double heldout_gap(const std::vector<ReplayModel>& per_fold, const std::vector<Fold>& folds, std::size_t horizon) {
  GapSum s;
  for (std::size_t f = 0; f < folds.size(); ++f)
    for (const auto* r : folds[f].test) s += windowed_sse(per_fold[f], *r, horizon);
  return s.rms_mm();
}

struct Trial {
  Models models;
  double heldout_gap_mm = 0;
  std::size_t evaluations = 0;
};

// Fits `kinds` on top of `base` in every fold (and on all training runs), scores held out.
Trial trial(const Models& base, std::span<const EffectKind> kinds, const std::vector<Fold>& folds,
            const std::vector<const core::Run*>& train, bool all_is_fold0, const FitOptions& fo) {
  Trial t;
  for (std::size_t f = 0; f < folds.size(); ++f) {
    auto fit = fit_effects(base.per_fold[f], kinds, folds[f].train, fo);
    t.evaluations += fit.evaluations;
    t.models.per_fold.push_back(std::move(fit.model));
  }
  if (all_is_fold0) {
    t.models.all = t.models.per_fold[0];
  } else {
    auto fit = fit_effects(base.all, kinds, train, fo);
    t.evaluations += fit.evaluations;
    t.models.all = std::move(fit.model);
  }
  t.heldout_gap_mm = heldout_gap(t.models.per_fold, folds, fo.horizon);
  return t;
}

std::optional<EffectKind> partner(EffectKind k) {
  switch (k) {
    case EffectKind::kInputDelay: return EffectKind::kValveLag;
    case EffectKind::kValveLag: return EffectKind::kInputDelay;
    case EffectKind::kDeadzoneShift: return EffectKind::kStaticFriction;
    case EffectKind::kStaticFriction: return EffectKind::kDeadzoneShift;
    default: return std::nullopt;
  }
}

double reduction(double before, double after) { return before > 0 ? 100.0 * (1.0 - after / before) : 0.0; }

std::string names(const std::vector<EffectKind>& kinds) {
  std::string s;
  for (auto k : kinds) s += (s.empty() ? "" : ", ") + std::string(plant::to_string(k));
  return s;
}

}  // namespace

std::vector<Fold> make_folds(const std::vector<const core::Run*>& train, const std::vector<const core::Run*>& heldout) {
  if (!heldout.empty()) return {Fold{train, heldout}};
  std::vector<Fold> folds;
  for (std::size_t i = 0; i < train.size(); ++i) {
    Fold f;
    for (std::size_t j = 0; j < train.size(); ++j) (i == j ? f.test : f.train).push_back(train[j]);
    folds.push_back(std::move(f));
  }
  return folds;
}

Diagnosis diagnose(const ReplayModel& nominal, const std::vector<const core::Run*>& train,
                   const std::vector<const core::Run*>& heldout, const DiagnosisOptions& o) {
  auto say = [&](const std::string& line) { if (o.progress) o.progress(line); };
  char buf[300];
  Diagnosis d;
  d.horizon = o.horizon;
  d.cross_validated = heldout.empty();
  const auto folds = make_folds(train, heldout);
  const bool all_is_fold0 = !d.cross_validated;
  const FitOptions fo{.horizon = o.horizon};

  Models current{std::vector<ReplayModel>(folds.size(), nominal), nominal};
  d.nominal = nominal;
  d.baseline_gap_mm = heldout_gap(current.per_fold, folds, o.horizon);
  d.train_gap_mm = windowed_gap_mm(nominal, train, o.horizon);
  std::snprintf(buf, sizeof buf, "baseline: held-out gap %.3f mm (training %.3f mm), %zu fold(s)", d.baseline_gap_mm,
                d.train_gap_mm, folds.size());
  say(buf);

  // 1. The nominal model's own parameters (gain, break points), re-fitted: on a rig much of a
  // gap is parameters that are off. They stay free in every later fit.
  const std::vector<EffectKind> nominal_kinds = {EffectKind::kGainChange, EffectKind::kDeadzoneShift};
  {
    auto t = trial(current, nominal_kinds, folds, train, all_is_fold0, fo);
    d.refit = t.models.all;
    d.refit_gap_mm = t.heldout_gap_mm;
    d.evaluations += t.evaluations;
    current = std::move(t.models);
    std::snprintf(buf, sizeof buf, "re-fit of gain and break points: held-out gap %.3f mm (%s)", d.refit_gap_mm,
                  d.refit.effects.describe().c_str());
    say(buf);
  }

  // 2. Forward selection over the structural effects, each fitted together with the nominal
  // parameters; its first round scores every candidate.
  double gap = d.refit_gap_mm;
  std::vector<EffectKind> remaining;
  for (auto k : o.candidates)
    if (std::find(nominal_kinds.begin(), nominal_kinds.end(), k) == nominal_kinds.end()) remaining.push_back(k);
  for (std::size_t round = 0; round < o.max_effects && !remaining.empty(); ++round) {
    std::vector<std::future<Trial>> futures;
    for (auto kind : remaining)
      futures.push_back(std::async(std::launch::async, [&, kind] {
        const std::vector<EffectKind> kinds = {kind, EffectKind::kGainChange, EffectKind::kDeadzoneShift};
        return trial(current, kinds, folds, train, all_is_fold0, fo);
      }));
    std::vector<Trial> trials;
    for (auto& f : futures) trials.push_back(f.get());
    std::size_t best = 0;
    for (std::size_t i = 0; i < trials.size(); ++i) {
      d.evaluations += trials[i].evaluations;
      if (trials[i].heldout_gap_mm < trials[best].heldout_gap_mm) best = i;
      if (round == 0)
        d.candidates.push_back({remaining[i], trials[i].models.all.effects.params(remaining[i]), trials[i].heldout_gap_mm,
                                reduction(d.baseline_gap_mm, trials[i].heldout_gap_mm),
                                reduction(d.refit_gap_mm, trials[i].heldout_gap_mm),
                                chance_threshold_pct(remaining[i]) * o.threshold_scale, false});
    }
    const EffectKind kind = remaining[best];
    SelectionStep step{kind, gap, trials[best].heldout_gap_mm, reduction(gap, trials[best].heldout_gap_mm),
                       chance_threshold_pct(kind) * o.threshold_scale, false};
    step.accepted = step.reduction_pct > step.threshold_pct;
    std::snprintf(buf, sizeof buf, "round %zu: best %s, held-out gap %.3f -> %.3f mm (%.1f %%, chance threshold %.1f %%): %s",
                  round + 1, std::string(plant::to_string(kind)).c_str(), gap, step.gap_after_mm, step.reduction_pct,
                  step.threshold_pct, step.accepted ? "accepted" : "not accepted");
    say(buf);
    d.steps.push_back(step);
    if (!step.accepted) break;
    if (const auto p = partner(kind)) {
      for (std::size_t i = 0; i < remaining.size(); ++i) {
        if (remaining[i] != *p) continue;
        const double r = reduction(gap, trials[i].heldout_gap_mm);
        if (r > chance_threshold_pct(*p) * o.threshold_scale && r >= o.confusable_ratio * step.reduction_pct)
          d.confusable.emplace_back(kind, *p);
      }
    }
    d.effects.push_back(kind);
    current = std::move(trials[best].models);
    gap = step.gap_after_mm;
    remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(best));
    // A confusable partner is not added on top: it would explain the same part twice.
    for (const auto& [a, b] : d.confusable)
      if (a == kind) std::erase(remaining, b);
  }
  d.final_model = current.all;
  d.final_gap_mm = gap;

  // 3. The nominal parameters are named when, fitted with the accepted effects, they lie beyond
  // what the model's own precision and noise give (tolerances calibrated on effect-free data) and
  // the re-fit beat chance.
  const bool refit_significant = reduction(d.baseline_gap_mm, d.refit_gap_mm) > o.refit_threshold_pct * o.threshold_scale;
  const auto& fe = d.final_model.effects;
  std::vector<EffectKind> named;
  if (refit_significant && std::abs(fe.param(EffectKind::kGainChange, 0) - 1.0) > o.gain_tolerance)
    named.push_back(EffectKind::kGainChange);
  if (refit_significant && std::max(std::abs(fe.param(EffectKind::kDeadzoneShift, 0)), std::abs(fe.param(EffectKind::kDeadzoneShift, 1))) >
                               o.shift_tolerance_V)
    named.push_back(EffectKind::kDeadzoneShift);
  d.effects.insert(d.effects.begin(), named.begin(), named.end());
  // Alone on the nominal model, for the candidate table.
  for (auto kind : nominal_kinds) {
    if (std::find(o.candidates.begin(), o.candidates.end(), kind) == o.candidates.end()) continue;
    Models nominal_models{std::vector<ReplayModel>(folds.size(), nominal), nominal};
    auto t = trial(nominal_models, std::span<const EffectKind>(&kind, 1), folds, train, all_is_fold0, fo);
    d.evaluations += t.evaluations;
    d.candidates.push_back({kind, fe.params(kind), t.heldout_gap_mm, reduction(d.baseline_gap_mm, t.heldout_gap_mm),
                            reduction(d.refit_gap_mm, t.heldout_gap_mm), o.refit_threshold_pct * o.threshold_scale, false});
  }
  std::stable_sort(d.candidates.begin(), d.candidates.end(),
                   [](const CandidateScore& a, const CandidateScore& b) { return a.heldout_gap_mm < b.heldout_gap_mm; });
  for (auto& c : d.candidates) c.accepted = std::find(d.effects.begin(), d.effects.end(), c.kind) != d.effects.end();
  // The final model carries only what is named: unnamed nominal parameters stay re-fitted (they
  // are the model's own), and are reported as the re-fit.

  std::vector<const core::Run*> all_runs = train;
  all_runs.insert(all_runs.end(), heldout.begin(), heldout.end());
  d.noise_std_mm = estimate_noise_std_mm(all_runs, nominal.model.dead_zone);
  d.noise_floor_mm = noise_floor_mm(nominal.model, d.noise_std_mm, o.horizon);
  d.unexplained = d.final_gap_mm > o.unexplained_factor * d.noise_floor_mm;
  // 4. The sensor's resolution: readings on a grid whose rounding error (step / sqrt(12)) is at
  // least the noise are a coarse sensor. A replay cannot predict the rounding, so this raises the
  // floor the gap can reach rather than shrinking the gap; the verdict uses that floor.
  const bool quantization_candidate =
      std::find(o.candidates.begin(), o.candidates.end(), EffectKind::kSensorQuantization) != o.candidates.end();
  if (const auto step = reading_resolution_mm(all_runs); step && quantization_candidate && *step / std::sqrt(12.0) >= d.noise_std_mm) {
    d.noise_floor_mm = noise_floor_mm(nominal.model, std::hypot(d.noise_std_mm, *step / std::sqrt(12.0)), o.horizon);
    std::snprintf(buf, sizeof buf, "readings lie on a %.4g mm grid, coarser than the noise: with its rounding the floor is %.3f mm",
                  *step, d.noise_floor_mm);
    say(buf);
    d.effects.push_back(EffectKind::kSensorQuantization);
    d.final_model.effects.set(EffectKind::kSensorQuantization, plant::EffectParams{*step, 0.0, 0.0});
    d.unexplained = d.final_gap_mm > o.unexplained_factor * d.noise_floor_mm;
    for (auto& c : d.candidates)
      if (c.kind == EffectKind::kSensorQuantization) c.params = plant::EffectParams{*step, 0.0, 0.0}, c.accepted = true;
  }
  std::snprintf(buf, sizeof buf, "verdict: %s; held-out gap %.3f -> %.3f mm; noise floor %.3f mm (sensor noise %.3f mm)%s",
                d.effects.empty() ? "no effect accepted" : names(d.effects).c_str(), d.baseline_gap_mm,
                d.final_gap_mm, d.noise_floor_mm, d.noise_std_mm, d.unexplained ? "; a significant gap remains unexplained" : "");
  say(buf);
  return d;
}

double estimate_noise_std_mm(const std::vector<const core::Run*>& runs, const core::DeadZone& dead_zone) {
  // At rest with the valve well inside the dead band for a while, the model's output is constant:
  // the second difference of the reading is the sensor's noise alone.
  constexpr std::size_t kQuiet = 10;
  constexpr double kMarginV = 0.1;
  std::vector<double> d2;
  for (const auto* r : runs) {
    const auto& y = r->y_mm;
    std::size_t quiet = 0;
    for (std::size_t k = 1; k + 1 < y.size(); ++k) {
      const bool inside = r->u_V[k] > dead_zone.b_l + kMarginV && r->u_V[k] < dead_zone.b_r - kMarginV;
      quiet = inside ? quiet + 1 : 0;
      if (quiet < kQuiet) continue;
      const double v = y[k + 1] - 2.0 * y[k] + y[k - 1];
      d2.push_back(v * v);
    }
  }
  if (d2.empty()) return 0.0;
  std::sort(d2.begin(), d2.end());
  d2.resize(std::max<std::size_t>(1, d2.size() * 95 / 100));  // trim slips and bumps
  double s = 0;
  for (double v : d2) s += v;
  // var(y(k+1) - 2y(k) + y(k-1)) = 6 sigma^2 for white noise; the 5 % trim takes about 13 % off it.
  return std::sqrt(s / static_cast<double>(d2.size()) / 6.0 / 0.87);
}

double noise_floor_mm(const core::HammersteinModel& model, double noise_std_mm, std::size_t horizon) {
  // A restart from noisy past outputs: the error at step j is sum_i h_j,i n_i - n_j, with h the
  // free response to a unit initial condition in slot i; the variance follows.
  const std::size_t na = model.A.size() - 1;
  std::vector<double> var(horizon, 1.0);
  for (std::size_t slot = 0; slot < na; ++slot) {
    std::array<double, core::kMaxModelOrder + 1> y{};
    y[slot] = 1.0;
    for (std::size_t j = 0; j < horizon; ++j) {
      double next = 0.0;
      for (std::size_t i = 1; i <= na; ++i) next -= model.A[i] * y[i - 1];
      for (std::size_t i = core::kMaxModelOrder; i > 0; --i) y[i] = y[i - 1];
      y[0] = next;
      var[j] += next * next;
    }
  }
  double mean = 0;
  for (double v : var) mean += v;
  return noise_std_mm * std::sqrt(mean / static_cast<double>(std::max<std::size_t>(1, horizon)));
}

}  // namespace epa::diag
