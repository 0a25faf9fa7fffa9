#include "report/whole_move_report.hpp"

#include <fmt/format.h>

#include "report/html.hpp"
#include "report/svg_chart.hpp"

namespace epa::report {

namespace {

std::vector<Panel> trace_panels(const diag::WholeMoveGap& w) {
  const auto& t = w.trace;
  Panel p{fmt::format("position over whole moves ({} run {})", t.set, t.index + 1), "time (s)", "position (mm)", {}, {}, {}, {}, {}, {}};
  p.series.push_back({"recorded", "#000000", t.t_s, t.measured_mm, false});
  p.series.push_back({"law's model, run free from each rest", "#d62728", t.t_s, t.law_model_mm, false});
  if (w.has_stick_slip) p.series.push_back({"stick-slip model, the same", "#1f77b4", t.t_s, t.stick_slip_mm, true});
  Panel s{"stick events: where the piston stands", "time (s)", "standing (1)", {}, {}, {}, {}, -0.1, 1.1};
  s.series.push_back({"recorded (readings at rest)", "#000000", t.t_s, t.recorded_rest, false});
  if (w.has_stick_slip) s.series.push_back({"stick-slip model stuck", "#1f77b4", t.t_s, t.model_stuck, true});
  return {p, s};
}

// Friction per kilogram of moving mass against the piston's speed: the sliding level while it
// moves, the band it holds up to while it sticks.
Panel friction_panel(const core::StickSlipParams& p) {
  Panel f{"stick-slip friction against the piston's speed", "speed (mm/s)", "friction per kg (m/s^2)", {}, {}, {}, {}, {}, {}};
  const double sliding = diag::sliding_m_s2(p), breakaway = diag::breakaway_m_s2(p);
  Series slide{"sliding", "#1f77b4", {}, {}, false}, stick{"sticking (holds up to)", "#d62728", {0.0, 0.0}, {-breakaway, breakaway}, true};
  for (double v = -100.0; v <= 100.0 + 1e-9; v += 1.0) {
    if (v == 0.0) slide.x.push_back(0.0), slide.y.push_back(NAN);  // the line breaks where it sticks
    else slide.x.push_back(v), slide.y.push_back(v > 0 ? sliding : -sliding);
  }
  f.series = {slide, stick};
  return f;
}

std::string terms_table(const diag::WholeMoveGap& w) {
  std::string h = "<table><tr><th>term</th><th>held-out gap without it, mm</th><th>cost, % of the law's model's gap</th><th>named</th></tr>\n";
  for (const auto& t : w.terms)
    h += std::string("<tr") + (t.named ? " class=\"yes\"" : "") + "><td>" + std::string(plant::to_string(t.effect)) + "</td><td>" +
         fmt::format("{:.3f}", t.heldout_without_mm) + "</td><td>" + fmt::format("{:.1f}", t.cost_pct) + "</td><td>" + (t.named ? "yes" : "") +
         "</td></tr>\n";
  return h + "</table>\n";
}

std::string changes_table(const diag::AxisChanges& c, const core::StickSlipParams& commissioned) {
  std::string h = fmt::format("<h3>Since commissioning</h3><p>Held-out gap against the commissioned model {:.3f} mm{}.</p>\n",
                              c.commissioned_heldout_mm, c.judged ? "" : "; changes not judged: the model file holds no spread");
  h += "<table><tr><th>change</th><th>fitted alone</th><th>held-out gap mm</th><th>reduction %</th><th>beyond the spread</th></tr>\n";
  for (const auto& k : c.candidates) {
    const bool named = c.accepted.has(k.term);
    h += std::string("<tr") + (named ? " class=\"yes\"" : "") + "><td>" + std::string(plant::to_string(diag::effect_of(k.term))) + "</td><td>" +
         escape_html(diag::describe_change(k.term, k.fit.change, commissioned)) + "</td><td>" + fmt::format("{:.3f}", k.fit.heldout_gap_mm) +
         "</td><td>" + fmt::format("{:.1f}", k.reduction_pct) + "</td><td>" + (k.beyond_tolerance ? "yes" : "") + "</td></tr>\n";
  }
  return h + "</table>\n";
}

}  // namespace

std::string render_whole_move_html(const diag::GapReport& r) {
  if (!r.whole_move) return "";
  const auto& w = *r.whole_move;
  std::string h = "<h2>Over whole moves</h2>\n<p>" +
                  escape_html(fmt::format("Each model runs free on the recorded valve command from where the piston rests, restarted at "
                                          "the mean of the readings there. {} segments judged, {} left out (an end stop{}); noise floor "
                                          "{:.3f} mm.",
                                          w.segments, w.segments_left_out,
                                          w.scoped_to_identified_drive ? fmt::format(", or driven outside the identified [{:g}, {:g}] V",
                                                                                     w.scope.drive_lo_v, w.scope.drive_hi_v)
                                                                       : std::string(),
                                          w.noise_floor_mm)) +
                  "</p>\n";
  if (!w.trace.t_s.empty()) h += inline_svg(render_svg("Recorded vs the law's model vs the stick-slip model", trace_panels(w), 1, 1100, 300));
  if (!w.has_stick_slip) return h;
  h += inline_svg(render_svg("Friction as mechanics, in physical units", {friction_panel(w.stick_slip)}, 1, 540, 280));
  h += terms_table(w);
  if (r.changes) h += changes_table(*r.changes, w.stick_slip);
  return h;
}

}  // namespace epa::report
