#include "report/svg_chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <string_view>
#include <tuple>
#include <utility>

namespace epa::report {

namespace {

constexpr int kTitleHeight = 40;
constexpr int kMarginLeft = 70, kMarginRight = 16, kMarginTop = 30, kMarginBottom = 48;
constexpr int kMinPanelWidth = 200, kMinPanelHeight = 140, kMaxPanelSize = 10000;
constexpr double kMaxPx = 1e6;  // far-off coordinates are clamped; the clipPath hides them
constexpr double kMargin = 0.05;
constexpr std::string_view kPalette[] = {"#1f77b4", "#d62728", "#2ca02c",
                                         "#ff7f0e", "#9467bd", "#8c564b"};
constexpr std::string_view kBandColors[] = {"#ff9900", "#7f7f7f", "#17becf"};
constexpr double kInf = INFINITY;

struct Pt {
  double x, y;
};
struct Range {
  double lo, hi;
};
using Runs = std::vector<std::vector<Pt>>;

// Pixel coordinate with at most 2 decimals, trailing zeros trimmed, never nan/inf.
std::string px(double v) {
  char buf[32];
  int n = std::snprintf(buf, sizeof buf, "%.2f",
                        std::isfinite(v) ? std::clamp(v, -kMaxPx, kMaxPx) : 0.0);
  while (n > 0 && buf[n - 1] == '0') --n;
  if (n > 0 && buf[n - 1] == '.') --n;
  std::string s(buf, static_cast<std::size_t>(n));
  return s == "-0" ? "0" : s;
}

void put_escaped(std::string& out, std::string_view s) {
  for (char c : s) {
    const char* entity = c == '&'    ? "&amp;"
                         : c == '<'  ? "&lt;"
                         : c == '>'  ? "&gt;"
                         : c == '"'  ? "&quot;"
                         : c == '\'' ? "&apos;"
                                     : nullptr;
    if (entity) out += entity;
    // Control characters other than tab/newline are not allowed in XML 1.0.
    else if (static_cast<unsigned char>(c) >= 0x20 || c == '\t' || c == '\n')
      out += c;
  }
}

// <name a="v"/>, or <name a="v">text</name> when text is given; everything is escaped here.
using Attrs = std::initializer_list<std::string_view>;  // key, value, key, value, ...
void tag(std::string& out, std::string_view name, Attrs attrs,
         std::optional<std::string_view> text = {}) {
  out.append("<").append(name);
  for (auto it = attrs.begin(); it != attrs.end() && it + 1 != attrs.end(); it += 2) {
    out.append(" ").append(*it).append("=\"");
    put_escaped(out, it[1]);
    out += '"';
  }
  if (!text) return out.append("/>\n"), void();
  out += '>';
  put_escaped(out, *text);
  out.append("</").append(name).append(">\n");
}

Range widen(double v) {
  const double half = (v == 0.0) ? 1.0 : std::abs(v) * 0.1;
  return {v - half, v + half};
}

// Decimals enough to tell ticks `step` apart.
std::string tick_label(double v, double step) {
  char buf[48];
  if (std::abs(v) < step * 1e-9) v = 0.0;
  if (std::abs(v) >= 1e7 || step < 1e-6) {
    std::snprintf(buf, sizeof buf, "%.6g", v);
  } else {
    const int decimals = std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 6);
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  }
  return buf;
}

// Axis range: explicit limits win; auto sides follow the data plus a 5% margin.
Range resolve_range(std::optional<double> lo_opt, std::optional<double> hi_opt, Range data) {
  const bool has_data = data.lo <= data.hi;
  const bool lo_set = lo_opt && std::isfinite(*lo_opt), hi_set = hi_opt && std::isfinite(*hi_opt);
  double lo = lo_set ? *lo_opt : (has_data ? data.lo : (hi_set ? *hi_opt - 1.0 : 0.0));
  double hi = hi_set ? *hi_opt : (has_data ? data.hi : lo + 1.0);
  if (lo > hi) std::swap(lo, hi);
  const double span = hi - lo;
  if (span == 0.0) return widen(lo);
  if (!lo_set) lo -= kMargin * span;
  if (!hi_set) hi += kMargin * span;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !std::isfinite(hi - lo)) return {0.0, 1.0};
  return {lo, hi};
}

// Liang-Barsky: clips segment a-b to the box xr x yr; false if nothing is left.
bool clip(Pt& a, Pt& b, Range xr, Range yr) {
  const Pt a0 = a, d{b.x - a.x, b.y - a.y};
  double t0 = 0.0, t1 = 1.0;
  for (const auto& [p, dp, r] : {std::tuple{a0.x, d.x, xr}, std::tuple{a0.y, d.y, yr}}) {
    if (dp == 0.0) {
      if (p < r.lo || p > r.hi) return false;
      continue;
    }
    const double ta = (r.lo - p) / dp, tb = (r.hi - p) / dp;
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  if (!(t0 <= t1)) return false;
  if (t0 > 0.0) a = {a0.x + t0 * d.x, a0.y + t0 * d.y};
  if (t1 < 1.0) b = {a0.x + t1 * d.x, a0.y + t1 * d.y};
  return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(b.x) && std::isfinite(b.y);
}

// Continuous runs of the series inside the x range, in data units. Segments leaving the range
// end at its edge, so far-off points themselves never reach the output.
Runs clip_runs(const Series& s, Range xr) {
  Runs runs;
  std::vector<Pt> cur;
  const auto flush = [&] {
    if (!cur.empty()) runs.push_back(std::move(cur));
    cur.clear();
  };
  std::optional<Pt> prev;
  for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
    const Pt p{s.x[i], s.y[i]};
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      flush();
      prev.reset();
      continue;
    }
    Pt a = prev.value_or(p), b = p;
    if (!clip(a, b, xr, {-kInf, kInf})) {
      flush();
    } else {
      if (cur.empty()) cur.push_back(a);
      if (b.x != cur.back().x || b.y != cur.back().y) cur.push_back(b);
      if (b.x != p.x) flush();  // left the range
    }
    prev = p;
  }
  flush();
  return runs;
}

// Per pixel column keeps the first, lowest, highest and last point in their original order:
// the drawn envelope is that of the full series, one-sample spikes included.
std::vector<Pt> decimate(const std::vector<Pt>& run) {
  std::vector<Pt> out;
  for (std::size_t i = 0, j = 0; i < run.size(); i = j) {
    std::size_t lo = i, hi = i;
    for (j = i; j < run.size() && std::floor(run[j].x) == std::floor(run[i].x); ++j) {
      if (run[j].y < run[lo].y) lo = j;
      if (run[j].y > run[hi].y) hi = j;
    }
    const std::size_t keep[] = {i, std::min(lo, hi), std::max(lo, hi), j - 1};
    for (std::size_t k = 0; k < 4; ++k)
      if (k == 0 || keep[k] != keep[k - 1]) out.push_back(run[keep[k]]);
  }
  return out;
}

struct Layout {  // render_svg's arguments, clamped to something drawable
  int columns, panel_width, panel_height;
  Layout(int columns_in, int panel_count, int width, int height)
      : columns(std::clamp(columns_in, 1, std::max(1, panel_count))),
        panel_width(std::clamp(width, kMinPanelWidth, kMaxPanelSize)),
        panel_height(std::clamp(height, kMinPanelHeight, kMaxPanelSize)) {}
  PlotRect rect(int index) const {
    const int col = index % columns, row = index / columns;
    return {double(col * panel_width + kMarginLeft),
            double(kTitleHeight + row * panel_height + kMarginTop),
            double(panel_width - kMarginLeft - kMarginRight),
            double(panel_height - kMarginTop - kMarginBottom)};
  }
};

std::vector<double> ticks_inside(Range r, int target) {
  std::vector<double> t = nice_ticks(r.lo, r.hi, target);
  const double eps = (r.hi - r.lo) * 1e-9;
  std::erase_if(t, [&](double v) { return v < r.lo - eps || v > r.hi + eps; });
  return t;
}

// Legend in the plot corner crossed by the fewest drawn segments, top-right on a tie.
void draw_legend(std::string& out, const Panel& p, const PlotRect& pr, const Runs& drawn) {
  struct Entry {
    std::string_view label, color;
    bool dashed, band;
  };
  std::vector<Entry> entries;
  for (std::size_t i = 0; i < p.series.size(); ++i) {
    const Series& s = p.series[i];
    if (!s.label.empty())
      entries.push_back({s.label, s.color.empty() ? kPalette[i % 6] : s.color, s.dashed, false});
  }
  for (std::size_t i = 0; i < p.bands.size(); ++i)
    if (!p.bands[i].label.empty())
      entries.push_back({p.bands[i].label, kBandColors[i % 3], false, true});
  if (entries.empty()) return;
  std::ptrdiff_t chars = 0;  // code points, not bytes, so boxes fit UTF-8 labels such as "µm"
  for (const Entry& e : entries)
    chars = std::max(chars, std::count_if(e.label.begin(), e.label.end(),
                                          [](char c) { return (c & 0xC0) != 0x80; }));
  const double w = 46.0 + 6.2 * static_cast<double>(chars),
               h = 8.0 + 16.0 * static_cast<double>(entries.size());
  const double left = pr.left + 8.0, right = pr.left + pr.width - 8.0 - w;
  const double top = pr.top + 8.0, bottom = pr.top + pr.height - 8.0 - h;
  Pt best{right, top};
  std::size_t best_hits = SIZE_MAX;
  for (const Pt corner : {Pt{right, top}, Pt{right, bottom}, Pt{left, top}, Pt{left, bottom}}) {
    std::size_t hits = 0;
    for (const auto& run : drawn)
      for (std::size_t i = 0; i < run.size(); ++i) {
        Pt a = run[i > 0 ? i - 1 : 0], b = run[i];
        hits += clip(a, b, {corner.x, corner.x + w}, {corner.y, corner.y + h});
      }
    if (hits < best_hits) best = corner, best_hits = hits;
  }
  const auto [x, y] = best;
  tag(out, "rect",
      {"x", px(x), "y", px(y), "width", px(w), "height", px(h), "fill", "white", "fill-opacity",
       "0.85", "stroke", "#bbbbbb"});
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    const double cy = y + 12.0 + 16.0 * static_cast<double>(i);
    if (e.band)
      tag(out, "rect",
          {"x", px(x + 8), "y", px(cy - 5), "width", "24", "height", "10", "fill", e.color,
           "fill-opacity", "0.25"});
    else
      tag(out, "line",
          {"x1", px(x + 8), "y1", px(cy), "x2", px(x + 32), "y2", px(cy), "stroke", e.color,
           "stroke-width", "2", "stroke-dasharray", e.dashed ? "6 4" : "none"});
    tag(out, "text", {"x", px(x + 38), "y", px(cy + 4)}, e.label);
  }
}

// Draws the series and adds its pixel runs to `drawn` (for the legend placement).
void draw_series(std::string& out, const Series& s, std::string_view fallback_color, Range xr,
                 Range yr, const PlotRect& pr, Runs& drawn) {
  const bool thin = static_cast<double>(std::min(s.x.size(), s.y.size())) > 2.0 * pr.width;
  for (const std::vector<Pt>& run : clip_runs(s, xr)) {
    std::vector<Pt> pts;
    pts.reserve(run.size());
    for (const Pt& p : run)
      pts.push_back({pr.left + (p.x - xr.lo) / (xr.hi - xr.lo) * pr.width,
                     pr.top + pr.height - (p.y - yr.lo) / (yr.hi - yr.lo) * pr.height});
    if (thin) pts = decimate(pts);
    const std::string_view color = s.color.empty() ? fallback_color : s.color;
    if (pts.size() == 1) {  // an isolated point would be invisible as a line
      tag(out, "circle", {"cx", px(pts[0].x), "cy", px(pts[0].y), "r", "2.5", "fill", color});
    } else {
      std::string points;
      for (const Pt& q : pts)
        points.append(points.empty() ? "" : " ").append(px(q.x) + "," + px(q.y));
      tag(out, "polyline",
          {"fill", "none", "stroke", color, "stroke-width", "1.6", "stroke-linejoin", "round",
           "stroke-dasharray", s.dashed ? "6 4" : "none", "points", points});
    }
    drawn.push_back(std::move(pts));
  }
}

void draw_panel(std::string& out, const Panel& p, int index, const PlotRect& pr) {
  // x extents over all finite points; y only over those inside the x range (so zooming in on
  // x rescales y), plus the bands.
  Range dx{kInf, -kInf}, dy{kInf, -kInf};
  const auto grow = [](Range& r, double v) { r = {std::min(r.lo, v), std::max(r.hi, v)}; };
  const auto each_point = [&](auto&& fn) {
    for (const Series& s : p.series)
      for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
        if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) fn(s.x[i], s.y[i]);
  };
  each_point([&](double x, double) { grow(dx, x); });
  const Range xr = resolve_range(p.x_min, p.x_max, dx);
  each_point([&](double x, double y) {
    if (x >= xr.lo && x <= xr.hi) grow(dy, y);
  });
  for (const Band& b : p.bands)
    if (std::isfinite(b.y_low) && std::isfinite(b.y_high)) grow(dy, b.y_low), grow(dy, b.y_high);
  const Range yr = resolve_range(p.y_min, p.y_max, dy);
  const auto sx = [&](double x) { return pr.left + (x - xr.lo) / (xr.hi - xr.lo) * pr.width; };
  const auto sy = [&](double y) {
    return pr.top + pr.height - (y - yr.lo) / (yr.hi - yr.lo) * pr.height;
  };
  const std::string left = px(pr.left), right = px(pr.left + pr.width), top = px(pr.top),
                    bottom = px(pr.top + pr.height), width = px(pr.width), height = px(pr.height),
                    id = "clip" + std::to_string(index);

  out += "<g>\n<clipPath id=\"" + id + "\">";
  tag(out, "rect", {"x", left, "y", top, "width", width, "height", height});
  out += "</clipPath>\n<g stroke=\"#e6e6e6\">\n";
  // About one tick per 70 px across and 28 px up (counting the ticks nice_ticks puts outside).
  const std::vector<double> xt = ticks_inside(xr, std::clamp(int(pr.width / 70), 3, 12));
  const std::vector<double> yt = ticks_inside(yr, std::clamp(int(pr.height / 28), 3, 12));
  for (double v : xt) tag(out, "line", {"x1", px(sx(v)), "y1", top, "x2", px(sx(v)), "y2", bottom});
  for (double v : yt) tag(out, "line", {"x1", left, "y1", px(sy(v)), "x2", right, "y2", px(sy(v))});
  out += "</g>\n<g font-size=\"11\" fill=\"#333333\">\n";
  const double x_step = xt.size() > 1 ? xt[1] - xt[0] : 1.0;
  const double y_step = yt.size() > 1 ? yt[1] - yt[0] : 1.0;
  for (double v : xt)
    tag(out, "text", {"x", px(sx(v)), "y", px(pr.top + pr.height + 16), "text-anchor", "middle"},
        tick_label(v, x_step));
  for (double v : yt)
    tag(out, "text", {"x", px(pr.left - 6), "y", px(sy(v) + 4), "text-anchor", "end"},
        tick_label(v, y_step));
  out += "</g>\n<g clip-path=\"url(#" + id + ")\">\n";
  for (std::size_t i = 0; i < p.bands.size(); ++i) {
    const Band& b = p.bands[i];
    if (!std::isfinite(b.y_low) || !std::isfinite(b.y_high)) continue;
    const double y0 = std::clamp(sy(std::max(b.y_low, b.y_high)), pr.top, pr.top + pr.height);
    const double y1 = std::clamp(sy(std::min(b.y_low, b.y_high)), pr.top, pr.top + pr.height);
    tag(out, "rect",
        {"x", left, "y", px(y0), "width", width, "height", px(std::max(y1 - y0, 1.0)), "fill",
         kBandColors[i % 3], "fill-opacity", "0.25"});
  }
  Runs drawn;
  for (std::size_t i = 0; i < p.series.size(); ++i)
    draw_series(out, p.series[i], kPalette[i % 6], xr, yr, pr, drawn);
  out += "</g>\n";
  // Frame, titles and legend on top of the data.
  tag(out, "rect",
      {"x", left, "y", top, "width", width, "height", height, "fill", "none", "stroke", "#444444"});
  const std::string mid_x = px(pr.left + pr.width / 2);
  tag(out, "text",
      {"x", mid_x, "y", px(pr.top - 10), "text-anchor", "middle", "font-size", "13", "font-weight",
       "bold"},
      p.title);
  tag(out, "text",
      {"x", mid_x, "y", px(pr.top + pr.height + 36), "text-anchor", "middle", "font-size", "12"},
      p.x_label);
  const std::string turn =
      "translate(" + px(pr.left - 52) + "," + px(pr.top + pr.height / 2) + ") rotate(-90)";
  tag(out, "text", {"transform", turn, "text-anchor", "middle", "font-size", "12"}, p.y_label);
  out += "<g font-size=\"11\">\n";
  draw_legend(out, p, pr, drawn);
  out += "</g>\n</g>\n";
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target_count) {
  if (!std::isfinite(lo) || !std::isfinite(hi)) return {};
  if (lo > hi) std::swap(lo, hi);
  if (lo == hi) std::tie(lo, hi) = std::pair(widen(lo).lo, widen(lo).hi);
  const double raw = (hi - lo) / std::max(target_count, 1);
  if (!std::isfinite(raw) || raw <= 0.0) return {lo, hi};
  // Smallest step m * 10^k (m in 1, 2, 5) not below raw; the tolerance keeps 0.6 / 6 at 0.1.
  const int k = static_cast<int>(std::floor(std::log10(raw)));
  const double mantissa = raw / std::pow(10.0, k) * (1.0 - 1e-9);
  const int m = mantissa <= 1.0 ? 1 : mantissa <= 2.0 ? 2 : mantissa <= 5.0 ? 5 : 10;
  const double step = m * std::pow(10.0, k);
  const double first = std::floor(lo / step + 1e-9), last = std::ceil(hi / step - 1e-9);
  if (!(last - first < 10000.0)) return {lo, hi};
  // i * m / 10^-k is the correctly rounded decimal (0.3, not 0.30000000000000004).
  const double scale = std::pow(10.0, std::abs(k));
  std::vector<double> ticks;
  for (double i = first; i <= last; i += 1.0)
    ticks.push_back(k < 0 ? i * m / scale : i * m * scale);
  return ticks;
}

PlotRect plot_rect(int index, int columns, int panel_count, int panel_width, int panel_height) {
  return Layout(columns, panel_count, panel_width, panel_height).rect(index);
}

std::string render_svg(const std::string& title, const std::vector<Panel>& panels, int columns,
                       int panel_width, int panel_height) {
  const int count = static_cast<int>(panels.size());
  const Layout l(columns, count, panel_width, panel_height);
  const int rows = (count + l.columns - 1) / l.columns;
  const std::string w = std::to_string(l.columns * l.panel_width);
  const std::string h = std::to_string(kTitleHeight + rows * l.panel_height);
  std::string out;
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + w + "\" height=\"" + h +
         "\" viewBox=\"0 0 " + w + " " + h + "\" font-family=\"sans-serif\">\n";
  tag(out, "rect", {"width", "100%", "height", "100%", "fill", "white"});
  tag(out, "text",
      {"x", px(l.columns * l.panel_width / 2.0), "y", "26", "text-anchor", "middle", "font-size",
       "16", "font-weight", "bold"},
      title);
  for (int i = 0; i < count; ++i)
    draw_panel(out, panels[static_cast<std::size_t>(i)], i, l.rect(i));
  out += "</svg>";
  return out;
}

}  // namespace epa::report
