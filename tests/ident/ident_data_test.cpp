#include "ident/ident_data.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace epa::ident {
namespace {

core::Run make_run(const std::vector<double>& y_mm, const std::vector<double>& u_V) {
  core::Run r;
  r.Ts = 0.01;
  for (std::size_t k = 0; k < y_mm.size(); ++k) r.t_s.push_back(0.01 * static_cast<double>(k));
  r.y_mm = y_mm;
  r.u_V = u_V;
  return r;
}

std::vector<double> repeat(double v, std::size_t n) { return std::vector<double>(n, v); }

std::vector<double> concat(std::initializer_list<std::vector<double>> parts) {
  std::vector<double> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

TEST(IdentData, ARunIsSplitAtTheEndStops) {
  // 100 samples at 250 mm, 10 at the lower stop, 60 at 250 mm, 5 at the upper stop, 20 inside.
  const auto y = concat({repeat(250, 100), repeat(0.3, 10), repeat(250, 60), repeat(499.5, 5), repeat(250, 20)});
  const auto run = make_run(y, repeat(1.0, y.size()));
  SegmentReport report;
  const auto s = split_run(run, "r.csv", {.min_segment = 50}, &report);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].size(), 100u);
  EXPECT_EQ(s[1].size(), 60u);
  EXPECT_EQ(report.samples_at_stops, 15u);
  EXPECT_EQ(report.samples_in_short, 20u);  // the last piece is shorter than min_segment
  EXPECT_DOUBLE_EQ(s[1].t0_s, 1.1);
  EXPECT_EQ(s[1].name, "r.csv [t 1.1-1.69 s]");
  EXPECT_DOUBLE_EQ(s[0].y[0], 5.0);  // 250 mm at 50 mm/V
}

TEST(IdentData, AWholeRunKeepsItsName) {
  const auto s = split_run(make_run(repeat(100, 80), repeat(0, 80)), "r.csv", {});
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "r.csv");
}

std::vector<Segment> moving_segments(std::size_t n) {
  Segment s{.name = "s", .t0_s = 0.0, .y = {}, .u = {}};
  for (std::size_t k = 0; k < n; ++k) {
    s.y.push_back(5.0 + 0.5 * std::sin(0.01 * static_cast<double>(k)));  // +-25 mm
    s.u.push_back(k % 100 < 50 ? 2.0 : -2.0);
  }
  return {s};
}

TEST(IdentData, TooFewSamplesAreRefusedWithWhatToDo) {
  auto s = check_excitation(moving_segments(100), "r.csv", {}, 50.0);
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("r.csv: 100 usable samples"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("--duration"), std::string::npos);
  EXPECT_TRUE(check_excitation(moving_segments(1000), "r.csv", {}, 50.0).has_value());
}

TEST(IdentData, AConstantCommandDoesNotExcite) {
  auto seg = moving_segments(1000);
  std::fill(seg[0].u.begin(), seg[0].u.end(), 0.7);
  auto s = check_excitation(seg, "r.csv", {}, 50.0);
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("does not excite"), std::string::npos) << s.error().message;
}

TEST(IdentData, APistonThatNeverMovesIsRefused) {
  auto seg = moving_segments(1000);
  std::fill(seg[0].y.begin(), seg[0].y.end(), 5.0);
  auto s = check_excitation(seg, "r.csv", {}, 50.0);
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("moves only 0 mm"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("--amplitude-max"), std::string::npos);
}

TEST(IdentData, OneWayCommandsCannotIdentifyBothSides) {
  auto seg = moving_segments(1000);
  for (double& u : seg[0].u) u = u > 0.0 ? 2.0 : 0.5;  // spans 1.5 V, never negative
  auto s = check_excitation(seg, "r.csv", {}, 50.0);
  ASSERT_FALSE(s.has_value());
  EXPECT_NE(s.error().message.find("one side of the dead zone"), std::string::npos) << s.error().message;
  EXPECT_TRUE(check_excitation(seg, "r.csv", {.need_both_directions = false}, 50.0).has_value());
}

}  // namespace
}  // namespace epa::ident
