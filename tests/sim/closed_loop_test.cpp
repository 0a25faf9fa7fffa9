// Closed-loop tests on the paper's plant: what the paper claims qualitatively (docs/paper.md explains why
// its numbers cannot all be reproduced from the printed model).
#include "sim/closed_loop.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "paper_steps.hpp"

namespace epa::sim {
namespace {

using control::ControllerKind;

using testing::kPaperStepsMm;
using testing::sign_changes_in_last_10s;
constexpr double kFfidzEssMm = 1.1;    // "FF-IDZ steady-state error within about 1 mm"
constexpr double kReachedMm = 2.0;     // "reaches the target": final value within 2 mm

StepRun paper_step(ControllerKind kind, double step_mm, double noise_mm = 0.0, double lc_mm = 5.0) {
  auto config = control::paper_controller_config(kind);
  config.lc_v = lc_mm / 50.0;
  auto params = control::ControllerParams::make(config);
  EXPECT_TRUE(params.has_value());
  auto r = simulate_step(core::paper::model(), *params, {.step_mm = step_mm, .noise_std_mm = noise_mm, .seed = 7});
  EXPECT_TRUE(r.has_value());
  EXPECT_EQ(r->faults, 0u);
  return *r;
}

TEST(PaperClosedLoop, PlainPpStallsInsideTheDeadZoneAndNeverReachesNinetyPercent) {
  for (double step : kPaperStepsMm) {
    const auto r = paper_step(ControllerKind::kPp, step);
    const double peak = *std::max_element(r.run.y_mm.begin(), r.run.y_mm.end());
    EXPECT_LT(peak, 0.9 * step) << step << " mm";
    const double last_valve = r.run.u_V.back();  // stalled: the command rests inside the band
    EXPECT_GT(last_valve, -1.722) << step << " mm";
    EXPECT_LT(last_valve, 1.232) << step << " mm";
    EXPECT_GT(r.metrics.ess_mm, 10.0) << step << " mm";
  }
}

TEST(PaperClosedLoop, PlainPpNeverLeavesRestOnTheSmallestStep) {
  const auto r = paper_step(ControllerKind::kPp, 25);  // u -> 1.625 e = 0.81 V < b_r: never moves
  EXPECT_FALSE(r.metrics.moved);
  EXPECT_FALSE(r.metrics.rise_s.has_value());
  EXPECT_NEAR(r.metrics.ess_mm, 25.0, 1e-9);
}

TEST(PaperClosedLoop, BothCompensatedControllersReachTheTarget) {
  for (ControllerKind kind : {ControllerKind::kPpNgidz, ControllerKind::kPpFfidz}) {
    for (double step : kPaperStepsMm) {
      const auto r = paper_step(kind, step);
      EXPECT_NEAR(r.metrics.final_mm, step, kReachedMm) << control::to_string(kind) << " " << step << " mm";
      EXPECT_TRUE(r.metrics.rise_s.has_value());
      EXPECT_TRUE(r.metrics.settling_s.has_value());
    }
  }
}

TEST(PaperClosedLoop, FfidzRisesFasterThanNgidzAtEveryStepSize) {
  for (double step : kPaperStepsMm) {
    const auto ng = paper_step(ControllerKind::kPpNgidz, step);
    const auto ff = paper_step(ControllerKind::kPpFfidz, step);
    ASSERT_TRUE(ng.metrics.rise_s && ff.metrics.rise_s);
    EXPECT_LT(*ff.metrics.rise_s, *ng.metrics.rise_s) << step << " mm";
  }
}

TEST(PaperClosedLoop, FfidzSteadyStateErrorIsWithinAboutOneMillimetre) {
  for (double step : kPaperStepsMm) EXPECT_LE(paper_step(ControllerKind::kPpFfidz, step).metrics.ess_mm, kFfidzEssMm) << step << " mm";
}

TEST(PaperClosedLoop, WithSensorNoiseNgidzChattersAndFfidzDoesNot) {
  for (double step : kPaperStepsMm) {
    const auto ng = paper_step(ControllerKind::kPpNgidz, step, /*noise_mm=*/0.1);
    const auto ff = paper_step(ControllerKind::kPpFfidz, step, /*noise_mm=*/0.1, /*lc_mm=*/5.0);
    EXPECT_GE(sign_changes_in_last_10s(ng), 200u) << step << " mm";  // one every ~50 ms or faster
    EXPECT_LE(sign_changes_in_last_10s(ff), 2u) << step << " mm";
  }
}

TEST(PaperClosedLoop, SeededRunsAreReproducible) {
  const auto a = paper_step(ControllerKind::kPpFfidz, 50, 0.1);
  const auto b = paper_step(ControllerKind::kPpFfidz, 50, 0.1);
  EXPECT_EQ(a.run.y_mm, b.run.y_mm);
  EXPECT_EQ(a.run.u_V, b.run.u_V);
}

TEST(PaperClosedLoop, RunRecordsTimingAndMetadata) {
  const auto r = paper_step(ControllerKind::kPpNgidz, 50);
  ASSERT_EQ(r.run.size(), 4000u);  // 20 s at 5 ms
  EXPECT_DOUBLE_EQ(r.run.t_s[1], 0.005);
  EXPECT_EQ(r.run.meta("controller"), "pp-ngidz");
  EXPECT_EQ(r.run.meta("source"), "sim");
  EXPECT_EQ(r.run.y_mm[0], 0.0);    // at rest at k = 0; the reference applies from k = 0
  EXPECT_EQ(r.run.r_mm[0], 50.0);
  EXPECT_EQ(r.run.uc_V.size(), r.run.u_V.size());
}

TEST(SimulateStep, RefusesTargetsOutsideTheStroke) {
  auto params = control::ControllerParams::make(control::paper_controller_config(ControllerKind::kPp));
  auto r = simulate_step(core::paper::model(), *params, {.step_mm = 600});
  ASSERT_FALSE(r.has_value());
  EXPECT_NE(r.error().message.find("outside the stroke"), std::string::npos);
}

TEST(CountSignChanges, SkipsZerosAndCountsFlips) {
  const double v[] = {0, 1, 2, 0, -1, -1, 0, 0, 3, -2};
  EXPECT_EQ(count_sign_changes(v), 3u);
}

}  // namespace
}  // namespace epa::sim
