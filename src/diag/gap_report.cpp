#include "diag/gap_report.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace epa::diag {

namespace {

using nlohmann::ordered_json;

double round_to(double v, double digits) {
  const double f = std::pow(10.0, digits);
  return std::round(v * f) / f;
}

ordered_json params_json(const plant::EffectSet& effects, plant::EffectKind kind, double Ts) {
  ordered_json p = ordered_json::object();
  const auto specs = plant::param_specs(kind);
  for (std::size_t i = 0; i < specs.size(); ++i) p[std::string(specs[i].name)] = round_to(effects.params(kind)[i], 4);
  if (kind == plant::EffectKind::kInputDelay) p["delay_s"] = round_to(effects.params(kind)[0] * Ts, 4);
  return p;
}

struct Scored {
  std::vector<WindowedReplay> replays;
  RegimeSums sums;
};

Scored score(const ReplayModel& m, const std::vector<NamedRun>& runs, const std::vector<SampleLabels>& labels,
             std::size_t horizon) {
  Scored s;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    s.replays.push_back(windowed_replay(m, *runs[i].run, horizon));
    s.sums.add(s.replays.back(), labels[i]);
  }
  return s;
}

}  // namespace

GapReport build_report(const Diagnosis& d, const std::vector<NamedRun>& train, const std::vector<NamedRun>& heldout,
                       const RegimeOptions& ro) {
  GapReport r;
  r.diagnosis = d;
  for (const auto& n : train) r.train_names.push_back(n.name);
  for (const auto& n : heldout) r.heldout_names.push_back(n.name);
  // Where: on the held-out runs; cross-validated, on all runs with the models fitted on all of
  // them (the breakdown, not the verdict, uses these in-sample figures).
  const auto& shown = heldout.empty() ? train : heldout;
  std::vector<const core::Run*> shown_runs;
  std::vector<SampleLabels> labels;
  for (const auto& n : shown) shown_runs.push_back(n.run), labels.push_back(label_samples(*n.run, d.nominal.model.dead_zone, ro));
  const Scored before = score(d.nominal, shown, labels, d.horizon);
  const Scored refit = score(d.refit, shown, labels, d.horizon);
  const Scored after = score(d.final_model, shown, labels, d.horizon);
  const auto sb = shares(before.sums), sr = shares(refit.sums), sa = shares(after.sums);
  for (std::size_t i = 0; i < sb.size(); ++i)
    r.where.push_back({sb[i], i < sr.size() ? sr[i].gap_mm : 0.0, i < sa.size() ? sa[i].gap_mm : 0.0,
                       i < sa.size() ? sa[i].gap_share_pct : 0.0});
  r.residuals_before = residual_stats(shown_runs, before.replays);
  r.residuals_after = residual_stats(shown_runs, after.replays);
  r.hints = hints(d.effects.empty() ? sb : sa, d.effects.empty() ? r.residuals_before : r.residuals_after);
  if (d.rest_drift.moving) {
    r.hints.insert(r.hints.begin(),
                   fmt::format("the readings move {:.2f} mm/s while the valve rests inside the dead band (median of {} rests): a drifting "
                               "sensor, a leaking valve or seal, or a load, none of them in the vocabulary",
                               d.rest_drift.median_speed_mm_s, d.rest_drift.rests));
  }

  auto add_runs = [&](const std::vector<NamedRun>& runs, const char* set) {
    for (const auto& n : runs) {
      const std::vector<const core::Run*> one{n.run};
      r.per_run.push_back({n.name, set, windowed_gap_mm(d.nominal, one, d.horizon), windowed_gap_mm(d.refit, one, d.horizon),
                           windowed_gap_mm(d.final_model, one, d.horizon)});
    }
  };
  add_runs(train, "train");
  add_runs(heldout, "heldout");

  if (!shown.empty()) {
    const auto& run = *shown.front().run;
    r.trace_name = shown.front().name;
    r.trace_t_s = run.t_s, r.trace_measured_mm = run.y_mm, r.trace_u_V = run.u_V;
    r.trace_nominal_mm.assign(run.size(), NAN), r.trace_final_mm.assign(run.size(), NAN);
    const auto& b = before.replays.front(), & a = after.replays.front();
    for (std::size_t i = 0; i < b.k.size(); ++i) r.trace_nominal_mm[b.k[i]] = b.predicted_mm[i];
    for (std::size_t i = 0; i < a.k.size(); ++i) r.trace_final_mm[a.k[i]] = a.predicted_mm[i];
  }
  return r;
}

std::string to_json(const GapReport& r) {
  const Diagnosis& d = r.diagnosis;
  const double Ts = d.nominal.model.Ts;
  ordered_json j;
  j["schema"] = "epa-gap-report/1";
  j["horizon_samples"] = d.horizon;
  j["runs"] = {{"train", r.train_names}, {"heldout", r.heldout_names}};
  j["baseline"] = {{"heldout_gap_mm", round_to(d.baseline_gap_mm, 4)},
                   {"windows", d.windows},
                   {"windows_at_end_stop", d.windows_at_end_stop}};
  ordered_json where = ordered_json::array();
  for (const auto& w : r.where)
    where.push_back({{"regime", w.before.regime},
                     {"time_share_pct", round_to(w.before.time_share_pct, 2)},
                     {"gap_share_pct", round_to(w.before.gap_share_pct, 2)},
                     {"dimension", w.before.dimension},
                     {"gap_before_mm", round_to(w.before.gap_mm, 4)},
                     {"gap_refit_mm", round_to(w.refit_gap_mm, 4)},
                     {"gap_after_mm", round_to(w.after_gap_mm, 4)},
                     {"gap_share_after_pct", round_to(w.after_gap_share_pct, 2)}});
  j["where"] = where;
  ordered_json candidates = ordered_json::array();
  for (const auto& c : d.candidates) {
    plant::EffectSet one;
    one.set(c.kind, c.params);
    candidates.push_back({{"effect", std::string(plant::to_string(c.kind))},
                          {"params", params_json(one, c.kind, Ts)},
                          {"heldout_gap_mm", round_to(c.heldout_gap_mm, 4)},
                          {"reduction_pct", round_to(c.reduction_pct, 2)},
                          {"accepted", c.accepted},
                          {"reduction_vs_refit_pct", round_to(c.reduction_vs_refit_pct, 2)},
                          {"chance_threshold_pct", round_to(c.threshold_pct, 2)}});
  }
  j["candidates"] = candidates;
  ordered_json verdict;
  std::vector<std::string> names;
  for (auto k : d.effects) names.emplace_back(plant::to_string(k));
  verdict["effects"] = names;
  verdict["unexplained"] = d.unexplained;
  verdict["heldout_gap_before_mm"] = round_to(d.baseline_gap_mm, 4);
  verdict["heldout_gap_after_mm"] = round_to(d.final_gap_mm, 4);
  verdict["reduction_pct"] = round_to(d.baseline_gap_mm > 0 ? 100.0 * (1.0 - d.final_gap_mm / d.baseline_gap_mm) : 0.0, 2);
  verdict["heldout_gap_refit_mm"] = round_to(d.refit_gap_mm, 4);
  ordered_json params = ordered_json::object();
  for (auto k : d.effects) params[std::string(plant::to_string(k))] = params_json(d.final_model.effects, k, Ts);
  verdict["params"] = params;
  ordered_json confusable = ordered_json::array();
  for (const auto& [a, b] : d.confusable) confusable.push_back({std::string(plant::to_string(a)), std::string(plant::to_string(b))});
  verdict["confusable"] = confusable;
  verdict["noise_floor_mm"] = round_to(d.noise_floor_mm, 4);
  verdict["text"] = verdict_text(r);
  j["verdict"] = verdict;

  // Beyond the keys docs/formats.md gives: the re-fit, per-run gaps, the selection steps, residual statistics.
  ordered_json refit_params = ordered_json::object();
  for (auto k : d.refit.effects.kinds()) refit_params[std::string(plant::to_string(k))] = params_json(d.refit.effects, k, Ts);
  j["refit"] = {{"params", refit_params}, {"heldout_gap_mm", round_to(d.refit_gap_mm, 4)}};
  ordered_json per_run = ordered_json::array();
  for (const auto& p : r.per_run)
    per_run.push_back({{"run", p.name}, {"set", p.set}, {"gap_before_mm", round_to(p.before_mm, 4)},
                       {"gap_refit_mm", round_to(p.refit_mm, 4)}, {"gap_after_mm", round_to(p.after_mm, 4)}});
  j["per_run"] = per_run;
  ordered_json steps = ordered_json::array();
  for (const auto& s : d.steps)
    steps.push_back({{"effect", std::string(plant::to_string(s.kind))}, {"gap_before_mm", round_to(s.gap_before_mm, 4)},
                     {"gap_after_mm", round_to(s.gap_after_mm, 4)}, {"reduction_pct", round_to(s.reduction_pct, 2)},
                     {"chance_threshold_pct", round_to(s.threshold_pct, 2)}, {"accepted", s.accepted}});
  j["selection"] = steps;
  auto stats = [](const ResidualStats& s) {
    std::vector<double> ac, cc;
    for (double v : s.autocorrelation) ac.push_back(round_to(v, 3));
    for (double v : s.input_crosscorrelation) cc.push_back(round_to(v, 3));
    return ordered_json{{"autocorrelation", ac}, {"input_crosscorrelation", cc},
                        {"peak_input_lag_samples", s.peak_input_lag}, {"peak_input_correlation", round_to(s.peak_input_correlation, 3)}};
  };
  j["residuals"] = {{"before", stats(r.residuals_before)}, {"after", stats(r.residuals_after)}};
  j["hints"] = r.hints;
  j["rest_drift"] = {{"rests", d.rest_drift.rests},
                     {"median_speed_mm_s", round_to(d.rest_drift.median_speed_mm_s, 4)},
                     {"threshold_mm_s", round_to(d.rest_drift.threshold_mm_s, 4)},
                     {"readings_move", d.rest_drift.moving}};
  j["cross_validated"] = d.cross_validated;
  j["noise_std_mm"] = round_to(d.noise_std_mm, 4);
  return j.dump(1) + "\n";
}

std::string verdict_text(const GapReport& r) {
  const Diagnosis& d = r.diagnosis;
  std::string s;
  if (d.effects.empty() && d.rest_drift.moving) {
    s = "Unexplained: the readings move while the valve rests inside the dead band, which no effect in the library does";
  } else if (d.effects.empty()) {
    s = d.unexplained ? "Unexplained: no effect in the library reduces the held-out gap beyond chance, and a significant gap remains"
                      : "No effect: the held-out gap is at the level of sensor noise and the model's own rounding";
  } else {
    plant::EffectSet named;  // the named effects only: unnamed re-fitted parameters are the model's own
    for (auto k : d.effects) named.set(k, d.final_model.effects.params(k));
    s = "The gap is explained by " + named.describe();
    for (const auto& [a, b] : d.confusable)
      s += "; " + std::string(plant::to_string(a)) + " and " + std::string(plant::to_string(b)) +
           " are confusable on these runs (either explains it)";
    if (d.unexplained) s += "; a significant gap remains unexplained";
  }
  s += fmt::format(". Held-out gap {:.3f} mm, {:.3f} mm after re-fitting gain and break points, {:.3f} mm with the accepted effects "
                   "(noise floor {:.3f} mm).",
                   d.baseline_gap_mm, d.refit_gap_mm, d.final_gap_mm, d.noise_floor_mm);
  if (d.windows_at_end_stop)
    s += fmt::format(" {} of {} windows touch an end stop and are left out of every gap.", d.windows_at_end_stop, d.windows);
  if (d.unexplained && !r.hints.empty()) s += " Where: " + r.hints.front() + ".";
  return s;
}

}  // namespace epa::diag
