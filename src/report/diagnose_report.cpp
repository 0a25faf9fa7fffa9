#include "report/diagnose_report.hpp"

#include <algorithm>
#include <cstdio>

#include "report/effect_shapes.hpp"
#include "report/html.hpp"
#include "report/svg_chart.hpp"
#include "report/whole_move_report.hpp"

namespace epa::report {

namespace {

std::string num(double v, const char* fmt = "%.3f") {
  char b[64];
  std::snprintf(b, sizeof b, fmt, v);
  return b;
}

}  // namespace

std::string render_diagnosis_html(const diag::GapReport& r) {
  const auto& d = r.diagnosis;
  std::string h = "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>epa diagnose: sim-to-real gap</title>"
                  "<style>body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse}"
                  "td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}td:first-child{text-align:left}"
                  ".yes{background:#d8f0d8}</style></head><body>\n<h1>Sim-to-real gap</h1>\n";
  h += "<p><b>" + escape_html(diag::verdict_text(r)) + "</b></p>\n";
  if (r.judged_on_whole_moves())
    h += "<p>The verdict is judged over whole moves (below), the measure on which friction shows. The windowed gap further "
         "down restarts the model from the readings and breaks the gap down by regime.</p>\n";
  h += "<p>Gap: RMS of the windowed prediction error, restarting the model from the measured state every " +
       std::to_string(d.horizon) + " samples. " + (d.cross_validated ? "Cross-validated by run." : "Scored on held-out runs.") + "</p>\n";
  if (!r.hints.empty()) {
    h += "<h2>Pointers</h2><ul>";
    for (const auto& s : r.hints) h += "<li>" + escape_html(s) + "</li>";
    h += "</ul>\n";
  }
  // Recorded vs nominal vs augmented, on the first scored run.
  if (!r.trace_t_s.empty()) {
    Panel p{"position: " + r.trace_name, "time (s)", "position (mm)", {}, {}, {}, {}, {}, {}};
    p.series.push_back({"recorded", "#000000", r.trace_t_s, r.trace_measured_mm, false});
    p.series.push_back({"nominal model (windowed)", "#d62728", r.trace_t_s, r.trace_nominal_mm, false});
    p.series.push_back({"with accepted effects", "#1f77b4", r.trace_t_s, r.trace_final_mm, true});
    Panel u{"valve command", "time (s)", "valve (V)", {}, {}, {}, {}, {}, {}};
    u.series.push_back({"u", "#2ca02c", r.trace_t_s, r.trace_u_V, false});
    u.bands.push_back({d.nominal.model.dead_zone.b_l, d.nominal.model.dead_zone.b_r, "dead band"});
    h += inline_svg(render_svg("Recorded vs nominal vs augmented model", {p, u}, 1, 1100, 320));
  }
  h += render_whole_move_html(r);
  if (const auto shapes = effect_shape_panels(d); !shapes.empty()) {
    h += "<h2>What was fitted: the named effects' shapes</h2>\n";
    h += inline_svg(render_svg("Fitted shapes, in physical units", shapes, 2, 540, 280));
  }
  // Share of the gap against share of the time as two bars per regime: a regime whose red bar
  // outgrows its grey one is where the model is wrong.
  h += "<h2>Where: gap per regime</h2><table><tr><th>dimension</th><th>regime</th><th>time % vs gap % (nominal)</th>"
       "<th>time %</th><th>gap %</th><th>gap mm nominal</th><th>after re-fit</th><th>with effects</th></tr>\n";
  auto bar = [](double pct, const char* color) {
    char b[160];
    std::snprintf(b, sizeof b, "<div style=\"background:%s;height:7px;margin:1px 0;width:%.1f%%\"></div>", color,
                  std::clamp(pct, 0.0, 100.0));
    return std::string(b);
  };
  for (const auto& w : r.where)
    h += "<tr><td>" + escape_html(w.before.dimension) + "</td><td>" + escape_html(w.before.regime) + "</td><td style=\"width:220px\">" +
         bar(w.before.time_share_pct, "#9e9e9e") + bar(w.before.gap_share_pct, "#d62728") + "</td><td>" +
         num(w.before.time_share_pct, "%.1f") + "</td><td>" + num(w.before.gap_share_pct, "%.1f") + "</td><td>" + num(w.before.gap_mm) +
         "</td><td>" + num(w.refit_gap_mm) + "</td><td>" + num(w.after_gap_mm) + "</td></tr>\n";
  h += "</table><p>Grey: share of the time; red: share of the gap (nominal model).</p>\n";
  h += "<h2>Which: candidates (held out)</h2><table><tr><th>effect</th><th>parameters</th><th>gap mm</th><th>reduction %</th>"
       "<th>vs re-fit %</th><th>chance %</th><th>accepted</th></tr>\n";
  for (const auto& c : d.candidates) {
    plant::EffectSet one;
    one.set(c.kind, c.params);
    h += std::string("<tr") + (c.accepted ? " class=\"yes\"" : "") + "><td>" + std::string(plant::to_string(c.kind)) + "</td><td>" +
         escape_html(one.describe()) + "</td><td>" + num(c.heldout_gap_mm) + "</td><td>" + num(c.reduction_pct, "%.1f") + "</td><td>" +
         num(c.reduction_vs_refit_pct, "%.1f") + "</td><td>" + num(c.threshold_pct, "%.1f") + "</td><td>" + (c.accepted ? "yes" : "") +
         "</td></tr>\n";
  }
  h += "</table>\n<h2>How far: per run</h2><table><tr><th>run</th><th>set</th><th>nominal mm</th><th>re-fit mm</th><th>with effects mm</th></tr>\n";
  for (const auto& p : r.per_run)
    h += "<tr><td>" + escape_html(p.name) + "</td><td>" + p.set + "</td><td>" + num(p.before_mm) + "</td><td>" + num(p.refit_mm) + "</td><td>" +
         num(p.after_mm) + "</td></tr>\n";
  h += "</table>\n<p>Final model: " + escape_html(d.final_model.effects.describe()) + ". Noise floor " + num(d.noise_floor_mm) +
       " mm (sensor noise " + num(d.noise_std_mm) + " mm).</p>\n</body></html>\n";
  return h;
}

}  // namespace epa::report
