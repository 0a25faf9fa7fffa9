// core::move_metrics on moves written out by hand, each figure worked out here from its definition
// (core/move_metrics.hpp), and which figures a move's end leaves n/a.
#include "core/move_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace epa::core {
namespace {

constexpr double kTs = 0.01;
const MoveMetricsOptions kOptions{.Ts = kTs, .ess_window_s = 0.02};  // the last 2 samples

// 0 -> 100 mm: 10 % at sample 1, 90 % at sample 3, 110 at sample 4 (10 % over), then within 2 mm
// (the 2 % band) from sample 6 on.
const std::vector<double> kArrives = {0, 10, 50, 95, 110, 103, 101, 100.5, 99.5};

TEST(MoveMetrics, AMoveInPositionHasEveryFigure) {
  const auto m = move_metrics(kArrives, 0.0, 100.0, MoveEnd::kInPosition, kOptions);
  EXPECT_DOUBLE_EQ(m.rise_s, 2 * kTs);          // samples 1 -> 3
  EXPECT_DOUBLE_EQ(m.overshoot_pct, 10.0);      // 110 against 100
  EXPECT_DOUBLE_EQ(m.settling_s, 6 * kTs);      // the last sample outside 2 mm is 5 (103)
  EXPECT_DOUBLE_EQ(m.ess_mm, 0.5);              // |100 - 100.5|, |100 - 99.5|
}

TEST(MoveMetrics, ADownwardMoveIsMeasuredTheSameWay) {
  std::vector<double> down;
  for (double y : kArrives) down.push_back(500.0 - y);
  const auto up = move_metrics(kArrives, 0.0, 100.0, MoveEnd::kInPosition, kOptions);
  const auto m = move_metrics(down, 500.0, 400.0, MoveEnd::kInPosition, kOptions);
  EXPECT_DOUBLE_EQ(m.rise_s, up.rise_s);
  EXPECT_DOUBLE_EQ(m.overshoot_pct, up.overshoot_pct);
  EXPECT_DOUBLE_EQ(m.settling_s, up.settling_s);
  EXPECT_DOUBLE_EQ(m.ess_mm, up.ess_mm);
}

TEST(MoveMetrics, StillOutsideTheBandAtTheEndHasNoSettling) {
  const std::vector<double> y = {0, 50, 90, 95};  // judged at 95: a timeout
  const auto m = move_metrics(y, 0.0, 100.0, MoveEnd::kTimeout, kOptions);
  EXPECT_TRUE(std::isnan(m.settling_s));
  EXPECT_DOUBLE_EQ(m.ess_mm, 7.5);  // |100 - 90|, |100 - 95|
  EXPECT_DOUBLE_EQ(m.overshoot_pct, 0.0);
}

TEST(MoveMetrics, AHaltedMoveHasNoOvershootNoSettlingAndNoSteadyState) {
  const auto m = move_metrics(kArrives, 0.0, 100.0, MoveEnd::kHalted, kOptions);
  EXPECT_DOUBLE_EQ(m.rise_s, 2 * kTs);
  EXPECT_TRUE(std::isnan(m.overshoot_pct));
  EXPECT_TRUE(std::isnan(m.settling_s));
  EXPECT_TRUE(std::isnan(m.ess_mm));
}

TEST(MoveMetrics, AMoveCutOnItsWayHasOnlyWhatItDid) {
  const std::vector<double> y = {0, 10, 50};  // cut at 50 mm: never at 90 %, never past the target
  const auto m = move_metrics(y, 0.0, 100.0, MoveEnd::kCutShort, kOptions);
  EXPECT_TRUE(std::isnan(m.rise_s));
  EXPECT_TRUE(std::isnan(m.overshoot_pct)) << "0 % would say it arrived cleanly";
  EXPECT_TRUE(std::isnan(m.settling_s));
  EXPECT_TRUE(std::isnan(m.ess_mm));
}

TEST(MoveMetrics, AMoveCutAfterPassingItsTargetKeepsItsOvershoot) {
  const std::vector<double> y = {0, 10, 50, 95, 110};
  const auto m = move_metrics(y, 0.0, 100.0, MoveEnd::kCutShort, kOptions);
  EXPECT_DOUBLE_EQ(m.overshoot_pct, 10.0);
  EXPECT_TRUE(std::isnan(m.settling_s));
  EXPECT_TRUE(std::isnan(m.ess_mm));
}

TEST(MoveMetrics, TheEndNamesReadBackAndAnUnknownOneIsRefused) {
  for (int i = 0; i < kMoveEnds; ++i) {
    const auto end = static_cast<MoveEnd>(i);
    EXPECT_EQ(parse_move_end(to_string(end)), end) << to_string(end);
  }
  EXPECT_FALSE(parse_move_end("complete").has_value());
}

}  // namespace
}  // namespace epa::core
