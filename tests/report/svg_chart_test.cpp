#include "report/svg_chart.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

namespace epa::report {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Xy {
  double x, y;
};

// Every point of every <polyline points="..."> in document order.
std::vector<std::vector<Xy>> polylines(const std::string& svg) {
  std::vector<std::vector<Xy>> out;
  const std::string key = "<polyline";
  for (std::size_t at = svg.find(key); at != std::string::npos; at = svg.find(key, at + 1)) {
    const std::size_t begin = svg.find("points=\"", at) + 8;
    const std::size_t end = svg.find('"', begin);
    std::vector<Xy> pts;
    const char* p = svg.c_str() + begin;
    const char* stop = svg.c_str() + end;
    while (p < stop) {
      char* next = nullptr;
      const double x = std::strtod(p, &next);
      const double y = std::strtod(next + 1, &next);  // skip the comma
      pts.push_back({x, y});
      p = next;
    }
    out.push_back(pts);
  }
  return out;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Tags nest and close properly (enough of XML well-formedness for a generated document).
bool tags_balanced(const std::string& svg) {
  std::vector<std::string> open;
  for (std::size_t at = svg.find('<'); at != std::string::npos; at = svg.find('<', at + 1)) {
    const std::size_t end = svg.find('>', at);
    if (end == std::string::npos) return false;
    const std::string tag = svg.substr(at + 1, end - at - 1);
    if (tag.empty()) return false;
    if (tag[0] == '/') {
      if (open.empty() || open.back() != tag.substr(1)) return false;
      open.pop_back();
    } else if (tag.back() != '/') {
      open.push_back(tag.substr(0, tag.find_first_of(" \n")));
    }
  }
  return open.empty();
}

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
  return n;
}

void expect_ticks(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_DOUBLE_EQ(got[i], want[i]) << "tick " << i;
}

TEST(NiceTicks, ZeroToTenStepsByTwo) {
  // 10 / 6 = 1.67 -> next 1-2-5 step is 2.
  expect_ticks(nice_ticks(0, 10), {0, 2, 4, 6, 8, 10});
}

TEST(NiceTicks, SmallRangeIsCoveredWithDecimalSteps) {
  // 0.37 / 6 = 0.062 -> step 0.1; the last tick 0.4 covers 0.37.
  const std::vector<double> t = nice_ticks(0, 0.37);
  expect_ticks(t, {0, 0.1, 0.2, 0.3, 0.4});
  EXPECT_EQ(t[3], 0.3);  // exactly the decimal, not 0.30000000000000004
}

TEST(NiceTicks, SymmetricRangeIsCovered) {
  // 10 / 6 = 1.67 -> step 2; -5 and 5 fall between ticks, so the cover is -6..6.
  expect_ticks(nice_ticks(-5, 5), {-6, -4, -2, 0, 2, 4, 6});
}

TEST(NiceTicks, DegenerateRangeIsWidened) {
  // 3 widens by 10% to [2.7, 3.3]: 0.6 / 6 = 0.1.
  expect_ticks(nice_ticks(3, 3), {2.7, 2.8, 2.9, 3.0, 3.1, 3.2, 3.3});
  // 0 widens to [-1, 1]: 2 / 6 = 0.33 -> step 0.5.
  expect_ticks(nice_ticks(0, 0), {-1, -0.5, 0, 0.5, 1});
}

TEST(NiceTicks, ReversedTargetAndNonFinite) {
  expect_ticks(nice_ticks(10, 0), {0, 2, 4, 6, 8, 10});
  // Target 3: 100 / 3 = 33 -> step 50.
  expect_ticks(nice_ticks(0, 100, 3), {0, 50, 100});
  // 25 / 6 = 4.2 -> step 5, covering 0.5 .. 24.5 from 0 to 25.
  expect_ticks(nice_ticks(0.5, 24.5), {0, 5, 10, 15, 20, 25});
  EXPECT_TRUE(nice_ticks(kNaN, 1).empty());
  EXPECT_TRUE(nice_ticks(0, kInf).empty());
}

Panel step_panel() {
  Panel p;
  p.title = "Step response";
  p.x_label = "time (s)";
  p.y_label = "position (mm)";
  Series y{"RST", "#1f77b4", {}, {}, false};
  Series r{"reference", "#000000", {0, 5}, {25, 25}, true};
  for (int i = 0; i <= 100; ++i) {
    y.x.push_back(i * 0.05);
    y.y.push_back(25.0 * (1.0 - std::exp(-i * 0.05 / 0.2)));
  }
  p.series = {y, r};
  p.bands = {{-1.722, 1.232, "dead band"}};
  p.x_min = 0;
  p.x_max = 5;
  return p;
}

TEST(RenderSvg, IsACompleteStandaloneDocument) {
  const std::string svg = render_svg("Closed loop", {step_panel(), step_panel()}, 2, 560, 300);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  ASSERT_GE(svg.size(), 6u);
  EXPECT_EQ(svg.substr(svg.size() - 6), "</svg>");
  EXPECT_NE(svg.find("xmlns=\"http://www.w3.org/2000/svg\""), std::string::npos);
  EXPECT_NE(svg.find("width=\"1120\" height=\"340\" viewBox=\"0 0 1120 340\""), std::string::npos);
  EXPECT_NE(svg.find("fill=\"white\""), std::string::npos);
  EXPECT_NE(svg.find("font-family=\"sans-serif\""), std::string::npos);
  EXPECT_TRUE(tags_balanced(svg));
  for (const char* text : {"Closed loop", "Step response", "time (s)", "position (mm)", "RST",
                           "reference", "dead band"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  EXPECT_EQ(count(svg, "stroke-dasharray=\"6 4\""), 4u);  // reference line + legend, twice
  EXPECT_EQ(count(svg, "<clipPath"), 2u);
  EXPECT_NE(svg.find("clip-path=\"url(#clip1)\""), std::string::npos);
}

TEST(RenderSvg, GridGrowsRowsAsNeeded) {
  const std::vector<Panel> panels(5, step_panel());
  const std::string svg = render_svg("grid", panels, 2, 400, 250);
  EXPECT_NE(svg.find("width=\"800\" height=\"790\""), std::string::npos);  // 40 + 3 rows x 250
  const PlotRect last = plot_rect(4, 2, 5, 400, 250);
  EXPECT_DOUBLE_EQ(last.left, 70);                // first column
  EXPECT_DOUBLE_EQ(last.top, 40 + 2 * 250 + 30);  // third row
  EXPECT_DOUBLE_EQ(last.width, 400 - 70 - 16);
}

TEST(RenderSvg, TickLabelsAreRoundNumbers) {
  Panel p = step_panel();
  p.y_min = 0;
  p.y_max = 0.37;
  const std::string svg = render_svg("t", {p});
  for (const char* label : {">0</text>", ">1</text>", ">5</text>", ">0.1</text>", ">0.3</text>"})
    EXPECT_NE(svg.find(label), std::string::npos) << label;
  EXPECT_EQ(svg.find(">0.4</text>"), std::string::npos);  // beyond y_max, not drawn
  EXPECT_EQ(svg.find("0000000"), std::string::npos);
}

TEST(RenderSvg, EscapesText) {
  Panel p;
  p.title = "u < b_l";
  p.series = {{"a&b \"c\" 'd'", "#123456", {0, 1}, {0, 1}, false}};
  const std::string svg = render_svg("<Step> & ramp", {p});
  EXPECT_NE(svg.find("&lt;Step&gt; &amp; ramp"), std::string::npos);
  EXPECT_NE(svg.find("u &lt; b_l"), std::string::npos);
  EXPECT_NE(svg.find("a&amp;b &quot;c&quot; &apos;d&apos;"), std::string::npos);
  EXPECT_EQ(svg.find("<Step>"), std::string::npos);
  EXPECT_TRUE(tags_balanced(svg));
}

TEST(RenderSvg, DegenerateInputsGiveNoNanOrInf) {
  Panel empty;
  Panel flat;
  flat.series = {{"flat", "", {0, 1, 2}, {4, 4, 4}, false}};
  Panel single;
  single.series = {{"single", "", {1}, {2}, false}};
  Panel mismatched;
  mismatched.series = {{"short", "", {0, 1, 2, 3}, {0, 1}, false}};
  Panel non_finite;
  non_finite.series = {{"nf", "", {0, 1, kNaN, 3, kInf, 5}, {kInf, 1, 2, -kInf, 4, kNaN}, false}};
  non_finite.bands = {{kNaN, 1, "bad band"}};
  Panel equal_limits = flat;
  equal_limits.x_min = equal_limits.x_max = 1;
  equal_limits.y_min = 3;
  equal_limits.y_max = 3;
  Panel reversed = flat;
  reversed.x_min = 2;
  reversed.x_max = 0;
  Panel bad_limits = flat;
  bad_limits.x_min = kNaN;
  bad_limits.y_max = kInf;
  const std::vector<Panel> panels{empty,      flat,         single,   mismatched,
                                  non_finite, equal_limits, reversed, bad_limits};
  for (int columns : {-3, 0, 1, 3, 100}) {
    const std::string svg = lower(render_svg("degenerate", panels, columns, 0, -5));
    EXPECT_EQ(svg.find("nan"), std::string::npos) << columns;
    EXPECT_EQ(svg.find("inf"), std::string::npos) << columns;
    EXPECT_TRUE(tags_balanced(svg)) << columns;
    EXPECT_EQ(svg.substr(svg.size() - 6), "</svg>");
  }
  EXPECT_TRUE(tags_balanced(render_svg("none", {})));

  // A single point is a dot; mismatched lengths use the shorter one (2 points).
  EXPECT_NE(render_svg("s", {single}).find("<circle"), std::string::npos);
  const auto lines = polylines(render_svg("m", {mismatched}));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].size(), 2u);
}

TEST(RenderSvg, NonFinitePointsBreakTheLine) {
  Panel p;
  p.series = {{"gap", "", {0, 1, 2, 3, 4, 5}, {0, 1, kNaN, 3, 4, 5}, false}};
  const auto lines = polylines(render_svg("gap", {p}));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].size(), 2u);
  EXPECT_EQ(lines[1].size(), 3u);
}

TEST(RenderSvg, DecimationKeepsASingleSampleSpike) {
  Panel p;
  Series s{"spiky", "", {}, {}, false};
  for (int i = 0; i < 20000; ++i) {
    s.x.push_back(i * 0.001);
    s.y.push_back(i == 10001 ? 100.0 : 0.0);
  }
  p.series = {s};
  p.y_min = 0;
  p.y_max = 100;
  const std::string svg = render_svg("spike", {p}, 1);
  const PlotRect r = plot_rect(0, 1, 1);
  const auto lines = polylines(svg);
  ASSERT_EQ(lines.size(), 1u);
  // Decimated: at most first/min/max/last per pixel column, far fewer than 20,000 points.
  EXPECT_LE(lines[0].size(), static_cast<std::size_t>(4 * (r.width + 2)));
  const double top = r.top, bottom = r.top + r.height;  // pixel rows of y = 100 and y = 0
  std::size_t at_top = 0;
  for (const Xy& q : lines[0]) {
    if (std::abs(q.y - top) < 0.006)
      ++at_top;
    else
      EXPECT_NEAR(q.y, bottom, 0.006);
  }
  EXPECT_EQ(at_top, 1u);
  // The spike sits at x = 10.001 s of 0 .. 19.999 s (auto range with 5% margin).
  const double span = 19.999 * 1.1;
  const double spike_x = r.left + (10.001 + 0.05 * 19.999) / span * r.width;
  const auto spike = std::find_if(lines[0].begin(), lines[0].end(),
                                  [&](const Xy& q) { return std::abs(q.y - top) < 0.006; });
  ASSERT_NE(spike, lines[0].end());
  EXPECT_NEAR(spike->x, spike_x, 0.006);
}

TEST(RenderSvg, PointsOutsideTheXLimitsAreClipped) {
  Panel p;
  p.series = {{"s", "", {0, 1, 2, 1000, 3, 4, 5000}, {0, 1, 2, 3, 4, 5, 6}, false}};
  p.x_min = 0;
  p.x_max = 4;
  const std::string svg = render_svg("clip", {p}, 1);
  const PlotRect r = plot_rect(0, 1, 1);
  const auto lines = polylines(svg);
  ASSERT_EQ(lines.size(), 2u);  // 0..2 then out to x = 1000, back in, 3..4
  for (const auto& line : lines)
    for (const Xy& q : line) {
      EXPECT_GE(q.x, r.left - 0.006);
      EXPECT_LE(q.x, r.left + r.width + 0.006);
    }
  // The first run ends where 2 -> 1000 crosses x = 4; the second starts where it comes back.
  EXPECT_NEAR(lines[0].back().x, r.left + r.width, 0.006);
  EXPECT_NEAR(lines[1].front().x, r.left + r.width, 0.006);
  EXPECT_NEAR(lines[1].back().x, r.left + r.width, 0.006);  // the point at x = 4
  EXPECT_NE(svg.find("clip-path=\"url(#clip0)\""), std::string::npos);
}

}  // namespace
}  // namespace epa::report
