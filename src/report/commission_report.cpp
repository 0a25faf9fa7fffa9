#include "report/commission_report.hpp"

#include <cstdio>

#include "report/html.hpp"
#include "report/svg_chart.hpp"

namespace epa::report {

namespace {

std::string number(const std::optional<double>& v, const char* format = "%.3f") {
  if (!v) return "never";
  char buf[32];
  std::snprintf(buf, sizeof buf, format, *v);
  return buf;
}

std::vector<double> times(std::size_t n, double Ts) {
  std::vector<double> t(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = static_cast<double>(i) * Ts;
  return t;
}

std::string moves_table(const std::vector<commission::JudgedMove>& moves) {
  std::string h = "<table><tr><th>move (mm)</th><th>rise (s)</th><th>settling (s)</th><th>e_ss (mm)</th><th>overshoot (%)</th><th></th></tr>";
  for (const auto& m : moves) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "<tr><td>%.1f &rarr; %.1f</td><td>", m.from_mm, m.to_mm);
    h += buf + number(m.metrics.rise_s) + "</td><td>" + number(m.metrics.settling_s) + "</td><td>" + number(m.metrics.ess_mm) +
         "</td><td>" + number(m.metrics.overshoot_pct, "%.1f") + "</td><td>" + (m.passed ? "pass" : escape_html_attribute(m.why)) + "</td></tr>";
  }
  return h + "</table>";
}

}  // namespace

std::string commission_report_html(const commission::CommissionOutcome& o) {
  std::string h = "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>Commissioning report</title><style>"
                  "body{font-family:sans-serif;margin:1.5em;max-width:1200px}table{border-collapse:collapse;margin:.5em 0}"
                  "td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}.verdict{font-size:1.3em;font-weight:bold}"
                  ".deployed{color:#176117}.rolled-back,.aborted{color:#a01818}svg{max-width:100%;height:auto}</style></head><body>";
  const std::string verdict(commission::to_string(o.verdict));
  h += "<h1>Commissioning report</h1><p class=\"verdict " + verdict + "\">" + verdict + ": " + escape_html_attribute(o.reason) + "</p>";
  h += "<p>previous tuning set: <b>" + escape_html_attribute(o.previous_set) + "</b>; new set: <b>" + (o.new_set.empty() ? "none stored" : escape_html_attribute(o.new_set)) +
       "</b></p>";

  if (!o.experiment.empty()) {
    h += "<h2>Experiment</h2>";
    std::vector<Panel> panels;
    for (std::size_t i = 0; i < o.experiment.size(); ++i) {
      const auto& r = o.experiment[i];
      const bool held_out = o.identified ? i == o.identified->held_out_run : i + 1 == o.experiment.size();
      Panel p{"run " + std::to_string(i + 1) + (held_out ? " (held out)" : " (estimation)"), "time (s)", "position (mm)", {}, {}, {}, {}, {}, {}};
      p.series.push_back({"measured", "#1f77b4", times(r.y_mm.size(), r.Ts), r.y_mm, false});
      if (held_out && o.identified && !o.identified->validation_simulated_mm.empty())
        p.series.push_back({"model, free run", "#d62728", times(o.identified->validation_simulated_mm.size(), r.Ts),
                            o.identified->validation_simulated_mm, true});
      panels.push_back(std::move(p));
      Panel u{"run " + std::to_string(i + 1) + ": valve command", "time (s)", "valve (V)", {}, {}, {}, {}, {}, {}};
      u.series.push_back({"", "#555", times(r.u_V.size(), r.Ts), r.u_V, false});
      if (o.identified) u.bands.push_back({o.identified->model.dead_zone.b_l, o.identified->model.dead_zone.b_r, "identified dead band"});
      panels.push_back(std::move(u));
    }
    h += render_svg("", panels, 2, 560, 240);
  }
  if (o.identified) {
    const auto& m = o.identified->model;
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "<h2>Identified model</h2><p>A = %s<br>B = %s<br>dead zone: b_l = %.3f V, b_r = %.3f V, m_l = %.4f, m_r = %.4f<br>"
                  "free-run fit: estimation %.1f %%, held-out run %.1f %%</p>",
                  m.A.to_string().c_str(), m.B.to_string().c_str(), m.dead_zone.b_l, m.dead_zone.b_r, m.dead_zone.m_l, m.dead_zone.m_r,
                  o.identified->estimation_fit_pct, o.identified->validation_fit_pct);
    h += buf + ("<p>" + escape_html_attribute(o.identified->summary) + "</p>");
  }
  if (o.design) {
    char buf[640];
    std::snprintf(buf, sizeof buf,
                  "<h2>Design</h2><p>%s, pole placement for %.1f %% overshoot and %.2f s settling (observer pole %.2f)<br>"
                  "F = %s<br>G = %s<br>T = %s<br>Sylvester condition number %.0f</p>",
                  std::string(control::to_string(o.spec.controller)).c_str(), o.spec.overshoot_pct, o.spec.settling_s,
                  o.spec.observer_pole, o.design->F.to_string().c_str(), o.design->G.to_string().c_str(),
                  o.design->T.to_string().c_str(), o.design->condition_number);
    h += buf;
  }
  if (o.simulation) {
    h += "<h2>Verification</h2><h3>In simulation</h3>";
    for (const auto& c : o.simulation->cases) h += "<p><b>" + escape_html_attribute(c.name) + "</b>: " + (c.passed ? "pass" : "FAIL") + "</p>" + moves_table(c.moves);
  }
  if (!o.verification.empty()) {
    h += "<h3>On the axis</h3>" + moves_table(o.verification);
    std::vector<Panel> panels;
    const auto* sim = o.simulation && !o.simulation->cases.empty() ? &o.simulation->cases.front() : nullptr;
    for (std::size_t i = 0; i < o.measured_moves.size(); ++i) {
      const auto& r = o.measured_moves[i];
      const auto& m = o.verification[i];
      char title[96];
      std::snprintf(title, sizeof title, "move %.1f -> %.1f mm", m.from_mm, m.to_mm);
      Panel p{title, "time (s)", "position (mm)", {}, {}, {}, {}, {}, {}};
      p.series.push_back({"measured", "#1f77b4", times(r.y_mm.size(), r.Ts), r.y_mm, false});
      if (sim && i < sim->positions_mm.size())
        p.series.push_back({"simulated (identified model)", "#ff7f0e", times(sim->positions_mm[i].size(), r.Ts), sim->positions_mm[i], true});
      p.series.push_back({"target", "#2ca02c", {0.0, r.duration_s()}, {m.to_mm, m.to_mm}, true});
      panels.push_back(std::move(p));
    }
    h += render_svg("", panels, 2, 560, 260);
  }
  h += "<h2>Log</h2><pre>";
  for (const auto& line : o.log) h += escape_html_attribute(line) + "\n";
  return h + "</pre></body></html>\n";
}

}  // namespace epa::report
