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

bool is_timing(plant::EffectKind k) { return k == plant::EffectKind::kInputDelay || k == plant::EffectKind::kValveLag; }

// The stick-slip model's term as the verdict gives its parameters, in its own units.
ordered_json mechanics_params(plant::EffectKind k, const core::StickSlipParams& p, double Ts) {
  switch (k) {
    case plant::EffectKind::kStaticFriction:
      return {{"breakaway_mm", round_to(p.static_mm, 4)}, {"sliding_mm", round_to(p.coulomb_mm, 4)},
              {"breakaway_m_s2", round_to(breakaway_m_s2(p), 4)}, {"sliding_m_s2", round_to(sliding_m_s2(p), 4)}};
    case plant::EffectKind::kValveLag: return {{"tau_s", round_to(p.spool_lag_s, 5)}};
    case plant::EffectKind::kInputDelay: return {{"delay_samples", p.delay_samples}, {"delay_s", round_to(p.delay_samples * Ts, 4)}};
    default: return ordered_json::object();
  }
}

// The effects the verdict names, each with the measure it shows on.
std::vector<std::pair<plant::EffectKind, const char*>> named_effects(const GapReport& r) {
  std::vector<std::pair<plant::EffectKind, const char*>> named;
  if (!r.judged_on_whole_moves()) {
    for (auto k : r.diagnosis.effects) named.emplace_back(k, "windowed");
    return named;
  }
  for (auto k : r.whole_move->named) named.emplace_back(k, "whole_move");
  // Timing shows best on the short windows: a delay or a lag they name stands beside.
  for (auto k : r.diagnosis.effects)
    if (is_timing(k) && std::find(r.whole_move->named.begin(), r.whole_move->named.end(), k) == r.whole_move->named.end())
      named.emplace_back(k, "windowed");
  return named;
}

ordered_json gap_sum_json(const GapSum& g) { return {{"gap_mm", round_to(g.rms_mm(), 4)}, {"segments", g.windows}}; }

ordered_json whole_move_json(const WholeMoveGap& w) {
  ordered_json j = {{"noise_floor_mm", round_to(w.noise_floor_mm, 4)},
                    {"segments", w.segments},
                    {"segments_left_out", w.segments_left_out},
                    {"drive_range_v", w.scoped_to_identified_drive ? ordered_json::array({w.scope.drive_lo_v, w.scope.drive_hi_v})
                                                                   : ordered_json(nullptr)},
                    {"law_model", {{"train", gap_sum_json(w.hammerstein_train)}, {"heldout", gap_sum_json(w.hammerstein_heldout)}}}};
  if (w.has_stick_slip) {
    ordered_json terms = ordered_json::array();
    for (const auto& t : w.terms)
      terms.push_back({{"effect", std::string(plant::to_string(t.effect))}, {"heldout_gap_without_mm", round_to(t.heldout_without_mm, 4)},
                       {"cost_pct", round_to(t.cost_pct, 2)}, {"named", t.named}});
    j["stick_slip"] = {{"train", gap_sum_json(w.stick_slip_train)}, {"heldout", gap_sum_json(w.stick_slip_heldout)},
                       {"explained_pct", round_to(w.explained_pct, 2)}, {"terms", terms}};
  }
  ordered_json per_run = ordered_json::array();
  for (const auto& p : w.per_run)
    per_run.push_back({{"set", p.set}, {"index", p.index}, {"law_model_gap_mm", round_to(p.hammerstein_mm, 4)},
                       {"stick_slip_gap_mm", w.has_stick_slip ? ordered_json(round_to(p.stick_slip_mm, 4)) : ordered_json(nullptr)},
                       {"segments", p.segments}, {"segments_left_out", p.segments_left_out}});
  j["per_run"] = per_run;
  return j;
}

ordered_json change_params_json(ChangeTerm k, const AxisChange& c) {
  ordered_json p = ordered_json::object();
  if (k == ChangeTerm::kDeadTime) return {{"delay_samples", c.delay_samples}};
  const auto* v = c.values_of(k);
  const auto specs = change_params(k, {});
  for (std::size_t i = 0; v && i < v->size() && i < specs.size(); ++i) p[specs[i].name] = round_to((*v)[i], 4);
  return p;
}

ordered_json changes_json(const AxisChanges& c, const core::StickSlipParams& commissioned) {
  ordered_json candidates = ordered_json::array();
  for (const auto& k : c.candidates)
    candidates.push_back({{"effect", std::string(plant::to_string(effect_of(k.term)))}, {"change", describe_change(k.term, k.fit.change, commissioned)},
                          {"params", change_params_json(k.term, k.fit.change)}, {"heldout_gap_mm", round_to(k.fit.heldout_gap_mm, 4)},
                          {"reduction_pct", round_to(k.reduction_pct, 2)}, {"beyond_tolerance", k.beyond_tolerance}});
  return {{"commissioned_heldout_gap_mm", round_to(c.commissioned_heldout_mm, 4)},
          {"commissioned_train_gap_mm", round_to(c.commissioned_train_mm, 4)},
          {"heldout_gap_after_mm", round_to(c.heldout_after_mm, 4)},
          {"threshold_pct", kChangeThresholdPct},
          {"judged", c.judged},
          {"candidates", candidates}};
}

void whole_move_verdict(ordered_json& verdict, const GapReport& r) {
  const WholeMoveGap& w = *r.whole_move;
  const double before = w.hammerstein_heldout.rms_mm(), after = w.stick_slip_heldout.rms_mm();
  verdict["unexplained"] = w.unexplained || (w.named.empty() && r.diagnosis.rest_drift.moving);
  verdict["heldout_gap_before_mm"] = round_to(before, 4);
  verdict["heldout_gap_after_mm"] = round_to(after, 4);
  verdict["reduction_pct"] = round_to(w.explained_pct, 2);
  verdict["heldout_gap_refit_mm"] = round_to(before, 4);
  ordered_json params = ordered_json::object();
  for (const auto& [k, measure] : named_effects(r))
    params[std::string(plant::to_string(k))] = std::string(measure) == "whole_move"
                                                   ? mechanics_params(k, w.stick_slip, r.diagnosis.nominal.model.Ts)
                                                   : params_json(r.diagnosis.final_model.effects, k, r.diagnosis.nominal.model.Ts);
  verdict["params"] = params;
  verdict["confusable"] = ordered_json::array();
  verdict["noise_floor_mm"] = round_to(w.noise_floor_mm, 4);
}

void changes_verdict(ordered_json& verdict, const GapReport& r) {
  const AxisChanges& c = *r.changes;
  std::vector<std::string> names;
  ordered_json detail = ordered_json::array();
  for (auto k : c.accepted.terms) {
    names.emplace_back(plant::to_string(effect_of(k)));
    detail.push_back({{"effect", std::string(plant::to_string(effect_of(k)))}, {"change", describe_change(k, c.accepted, r.whole_move->stick_slip)},
                      {"params", change_params_json(k, c.accepted)}});
  }
  if (c.sensor_step_mm) {
    names.emplace_back("sensor_quantization");
    detail.push_back({{"effect", "sensor_quantization"}, {"change", fmt::format("the readings lie on a grid of {:.4f} mm", *c.sensor_step_mm)},
                      {"params", {{"step_mm", round_to(*c.sensor_step_mm, 5)}}}});
  }
  verdict["changes"] = names;
  verdict["changes_detail"] = detail;
  verdict["changes_unexplained"] = c.unexplained;
  verdict["changes_gap_before_mm"] = round_to(c.commissioned_heldout_mm, 4);
  verdict["changes_gap_after_mm"] = round_to(c.heldout_after_mm, 4);
  verdict["changes_reduction_pct"] = round_to(c.reduction_pct, 2);
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
  ordered_json measures = ordered_json::object();
  for (const auto& [k, measure] : named_effects(r)) names.emplace_back(plant::to_string(k)), measures[std::string(plant::to_string(k))] = measure;
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
  if (r.judged_on_whole_moves()) whole_move_verdict(verdict, r);
  verdict["measure"] = r.judged_on_whole_moves() ? "whole_move" : "windowed";
  verdict["effect_measures"] = measures;
  if (r.changes) changes_verdict(verdict, r);
  verdict["text"] = verdict_text(r);
  j["verdict"] = verdict;
  if (r.whole_move) j["whole_move"] = whole_move_json(*r.whole_move);
  if (r.changes) j["changes"] = changes_json(*r.changes, r.whole_move->stick_slip);

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

namespace {

std::string mechanics_text(plant::EffectKind k, const core::StickSlipParams& p) {
  switch (k) {
    case plant::EffectKind::kStaticFriction:
      return fmt::format("static_friction (a stick state that follows the piston: breakaway {:.2f} m/s^2 and sliding {:.2f} m/s^2 "
                         "per kg of moving mass, {:.2f} and {:.2f} mm of the air spring's wind-up)",
                         breakaway_m_s2(p), sliding_m_s2(p), p.static_mm, p.coulomb_mm);
    case plant::EffectKind::kValveLag: return fmt::format("valve_lag (spool lag {:.1f} ms)", p.spool_lag_s * 1e3);
    case plant::EffectKind::kInputDelay: return fmt::format("input_delay ({} samples)", p.delay_samples);
    default: return std::string(plant::to_string(k));
  }
}

std::string whole_move_text(const GapReport& r) {
  const WholeMoveGap& w = *r.whole_move;
  const double before = w.hammerstein_heldout.rms_mm(), after = w.stick_slip_heldout.rms_mm();
  std::string s;
  if (!w.named.empty()) {
    s = "Over whole moves, the law's model lacks the axis's mechanics that the model file's stick-slip model holds: ";
    for (std::size_t i = 0; i < w.named.size(); ++i) s += (i ? ", " : "") + mechanics_text(w.named[i], w.stick_slip);
    s += fmt::format(". They explain {:.0f} % of its gap", w.explained_pct);
    if (w.unexplained) s += "; a significant gap remains unexplained";
  } else if (w.explained_pct >= kMechanicsThresholdPct) {
    s = fmt::format("Over whole moves the model file's stick-slip model follows the runs better than the law's model ({:.0f} % of its gap) "
                    "by its speeds and break points: none of its friction, spool lag or dead time accounts for {:.0f} % of the gap",
                    w.explained_pct, kMechanicsThresholdPct);
    if (w.unexplained) s += "; a significant gap remains unexplained";
  } else if (w.unexplained || r.diagnosis.rest_drift.moving) {
    s = "Unexplained: over whole moves neither the law's model nor the stick-slip model follows the runs";
  } else {
    s = "No effect: over whole moves the law's model follows the runs to the level of sensor noise";
  }
  for (const auto& [k, measure] : named_effects(r))
    if (std::string(measure) == "windowed") s += "; on short windows also " + std::string(plant::to_string(k));
  s += fmt::format(". Held-out gap over whole moves {:.3f} mm with the law's model, {:.3f} mm with the stick-slip model (noise floor {:.3f} mm; "
                   "{} segments from rest",
                   before, after, w.noise_floor_mm, w.segments);
  if (w.segments_left_out)
    s += fmt::format(", {} left out: at an end stop{}", w.segments_left_out,
                     w.scoped_to_identified_drive ? fmt::format(" or driven outside the identified [{:g}, {:g}] V", w.scope.drive_lo_v, w.scope.drive_hi_v) : "");
  return s + ").";
}

std::string changes_text(const GapReport& r) {
  const AxisChanges& c = *r.changes;
  std::string s = " Since commissioning: ";
  if (!c.judged) {
    s += "not judged: the model file does not say how far its stick-slip model's own terms spread (epa identify with --validate "
         "writes [stick_slip_spread])";
    if (c.unexplained) s += "; the readings move while the valve rests (a leak, a load or a drifting sensor)";
  } else if (c.accepted.terms.empty()) {
    s += c.unexplained ? "unexplained: the readings move while the valve rests (a leak, a load or a drifting sensor), which no change of "
                         "the model's terms does"
                       : "no change beyond the commissioned model's tolerance";
  } else {
    for (std::size_t i = 0; i < c.accepted.terms.size(); ++i)
      s += (i ? "; " : "") + std::string(plant::to_string(effect_of(c.accepted.terms[i]))) + ": " +
           describe_change(c.accepted.terms[i], c.accepted, r.whole_move->stick_slip);
    if (c.unexplained) s += "; and the readings move while the valve rests, which none of these does";
  }
  if (c.sensor_step_mm) s += fmt::format("; the sensor reads coarser: its readings lie on a grid of {:.4f} mm", *c.sensor_step_mm);
  return s + fmt::format(" (held-out gap {:.3f} mm against the commissioned model, {:.3f} mm with the changes).", c.commissioned_heldout_mm,
                         c.heldout_after_mm);
}

}  // namespace

std::string verdict_text(const GapReport& r) {
  if (r.judged_on_whole_moves()) return whole_move_text(r) + (r.changes ? changes_text(r) : std::string());
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
  if (r.whole_move)
    s += fmt::format(" Over whole moves from rest the gap is {:.3f} mm (noise floor {:.3f} mm).", r.whole_move->hammerstein_heldout.rms_mm(),
                     r.whole_move->noise_floor_mm);
  return s;
}

}  // namespace epa::diag
