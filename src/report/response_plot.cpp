#include "report/response_plot.hpp"

#include <algorithm>
#include <cstdio>

#include "report/svg_chart.hpp"

namespace epa::report {

namespace {

const char* color_of(control::ControllerKind k) {
  switch (k) {
    case control::ControllerKind::kPp: return "#7f7f7f";
    case control::ControllerKind::kPpNgidz: return "#1f77b4";
    case control::ControllerKind::kPpFfidz: return "#d62728";
    case control::ControllerKind::kPpTraj: return "#2ca02c";
  }
  return "#000000";
}

// The first `window_s` seconds of a column, as (t, value) for a series.
Series window_series(const SimulationCase& c, const std::vector<double>& column, double window_s, bool dashed = false) {
  Series s;
  s.label = std::string(control::display_name(c.kind));
  s.color = color_of(c.kind);
  s.dashed = dashed;
  const auto& t = c.result.run.t_s;
  for (std::size_t k = 0; k < t.size() && t[k] <= window_s; ++k) {
    s.x.push_back(t[k]);
    s.y.push_back(column[k]);
  }
  return s;
}

}  // namespace

std::string render_response_plot(const std::vector<SimulationCase>& cases, const core::DeadZone& dz, double window_s,
                                 const std::string& title) {
  std::vector<double> steps;
  for (const auto& c : cases)
    if (std::find(steps.begin(), steps.end(), c.step_mm) == steps.end()) steps.push_back(c.step_mm);

  std::vector<Panel> panels;
  for (double step : steps) {
    char name[64];
    std::snprintf(name, sizeof name, "%g mm step: position", step);
    Panel position{name, "time (s)", "position (mm)", {}, {}, 0.0, window_s, {}, {}};
    std::snprintf(name, sizeof name, "%g mm step: valve command", step);
    Panel valve{name, "time (s)", "valve command (V)", {}, {}, 0.0, window_s, -5.5, 5.5};
    valve.bands.push_back({dz.b_l, dz.b_r, "dead band"});
    bool reference_drawn = false;
    for (const auto& c : cases) {
      if (c.step_mm != step) continue;
      if (!reference_drawn) {
        Series ref = window_series(c, c.result.run.r_mm, window_s, /*dashed=*/true);
        ref.label = "reference";
        ref.color = "#000000";
        position.series.push_back(std::move(ref));
        reference_drawn = true;
      }
      position.series.push_back(window_series(c, c.result.run.y_mm, window_s));
      valve.series.push_back(window_series(c, c.result.run.u_V, window_s));
    }
    panels.push_back(std::move(position));
    panels.push_back(std::move(valve));
  }
  return render_svg(title, panels, 2);
}

}  // namespace epa::report
