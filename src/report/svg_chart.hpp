#pragma once
// A small, dependency-free SVG line-chart writer for `epa simulate`: step responses of the
// controllers and the valve command with the dead band shaded, laid out like a paper's figures.
// The output is a standalone SVG document a browser opens directly.
#include <optional>
#include <string>
#include <vector>

namespace epa::report {

struct Series {
  std::string label;         // legend text; empty = no legend entry
  std::string color;         // CSS colour, e.g. "#1f77b4"; empty = from a default palette
  std::vector<double> x, y;  // the shorter length is used; non-finite points break the line
  bool dashed = false;       // e.g. the reference trajectory
};

// A horizontal shaded band, e.g. the valve dead band [b_l, b_r].
struct Band {
  double y_low = 0, y_high = 0;
  std::string label;  // shown in the legend
};

struct Panel {
  std::string title, x_label, y_label;  // axis labels include units, e.g. "position (mm)"
  std::vector<Series> series;
  std::vector<Band> bands;
  // Axis limits; unset = from the data with a 5% margin. Points outside the x limits are clipped.
  std::optional<double> x_min, x_max, y_min, y_max;
};

// Lays panels out in a grid of `columns` columns (rows as needed), each panel
// `panel_width` x `panel_height` px, under a document title. Series with more points than twice
// the plot width are decimated min/max per pixel column, so one-sample spikes stay visible.
std::string render_svg(const std::string& title, const std::vector<Panel>& panels, int columns = 2,
                       int panel_width = 560, int panel_height = 300);

// About `target_count` tick values with a step of 1, 2 or 5 x 10^k covering [lo, hi]: the first
// tick is <= lo and the last >= hi. lo == hi is widened (by 10% of |lo|, or 1 around 0);
// reversed bounds are swapped; non-finite bounds give no ticks.
std::vector<double> nice_ticks(double lo, double hi, int target_count = 6);

// Where the plot area (inside the axes) of panel `index` lies in the document, in px. Exposed so
// callers and tests can map data values to pixels; arguments are clamped as render_svg does.
struct PlotRect {
  double left = 0, top = 0, width = 0, height = 0;
};
PlotRect plot_rect(int index, int columns, int panel_count, int panel_width = 560,
                   int panel_height = 300);

}  // namespace epa::report
