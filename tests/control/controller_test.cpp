#include "control/controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "control/paper_controller.hpp"

namespace epa::control {
namespace {

constexpr double kExact = 1e-12;  // the law is a handful of multiply-adds: no drift to tolerate

ControllerParams make_params(ControllerKind kind) {
  auto p = ControllerParams::make(paper_controller_config(kind));
  EXPECT_TRUE(p.has_value());
  return *p;
}

std::string error_of(const ControllerConfig& c) {
  auto p = ControllerParams::make(c);
  return p.has_value() ? std::string("(accepted)") : p.error().message;
}

TEST(ControllerParams, RefusesNonMonicF) {
  auto c = paper_controller_config(ControllerKind::kPp);
  c.F = {2.0, -1.778, 0.7828};
  EXPECT_NE(error_of(c).find("F must be monic"), std::string::npos) << error_of(c);
}

TEST(ControllerParams, RefusesNonPositiveSlopeNamingIt) {
  auto c = paper_controller_config(ControllerKind::kPpFfidz);
  c.dead_zone.m_l = 0.0;
  EXPECT_NE(error_of(c).find("m_l"), std::string::npos) << error_of(c);
  c = paper_controller_config(ControllerKind::kPpFfidz);
  c.dead_zone.m_r = -1.0;
  EXPECT_NE(error_of(c).find("m_r"), std::string::npos) << error_of(c);
}

TEST(ControllerParams, RefusesLeftBreakPointAboveRight) {
  auto c = paper_controller_config(ControllerKind::kPpNgidz);
  c.dead_zone.b_l = 2.0;  // above b_r = 1.232
  EXPECT_NE(error_of(c).find("b_l"), std::string::npos) << error_of(c);
}

TEST(ControllerParams, RefusesNanCoefficientNamingItsIndex) {
  auto c = paper_controller_config(ControllerKind::kPp);
  c.G = {-0.1734, std::numeric_limits<double>::quiet_NaN(), -0.3958};
  EXPECT_NE(error_of(c).find("G[1]"), std::string::npos) << error_of(c);
  c = paper_controller_config(ControllerKind::kPp);
  c.lc_v = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(error_of(c).find("l_c"), std::string::npos) << error_of(c);
}

TEST(ControllerParams, RefusesOrderAboveFixedStorage) {
  auto c = paper_controller_config(ControllerKind::kPp);
  c.F = core::Polynomial(std::vector<double>(kMaxLawOrder + 2, 0.1));
  EXPECT_NE(error_of(c).find("at most"), std::string::npos) << error_of(c);
}

TEST(ControllerParams, RefusesNonPositiveValveLimitAndSafeCommandOutsideIt) {
  auto c = paper_controller_config(ControllerKind::kPp);
  c.valve_limit_v = 0.0;
  EXPECT_NE(error_of(c).find("valve limit"), std::string::npos);
  c = paper_controller_config(ControllerKind::kPp);
  c.safe_valve_v = 6.0;
  EXPECT_NE(error_of(c).find("safe valve"), std::string::npos);
}

TEST(ControllerParams, EmptyHMeansErrorFeedbackHEqualsG) {
  const auto p = make_params(ControllerKind::kPp);
  EXPECT_EQ(p.rst().H, p.rst().G);
  EXPECT_EQ(p.rst().nH, 2u);
}

// The first samples of F u = G (r - y) computed by hand from eq 12-13 for a constant error e:
// u0 = g0 e; u1 = 1.778 u0 + (g0 + g1) e; u2 = 1.778 u1 - 0.7828 u0 + (g0 + g1 + g2) e.
TEST(PpLaw, FirstSamplesMatchTheRecursionByHand) {
  const auto p = make_params(ControllerKind::kPp);
  ControllerState s;
  const double e = 0.5;  // 25 mm in sensor volts
  const double u0 = -0.1734 * e;
  const double u1 = 1.778 * u0 + (-0.1734 + 0.577) * e;
  const double u2 = 1.778 * u1 - 0.7828 * u0 + (-0.1734 + 0.577 - 0.3958) * e;
  EXPECT_NEAR(controller_step(p, s, e, 0.0).valve_v, u0, kExact);
  EXPECT_NEAR(controller_step(p, s, e, 0.0).valve_v, u1, kExact);
  EXPECT_NEAR(controller_step(p, s, e, 0.0).valve_v, u2, kExact);
}

// G(1)/F(1) = 0.0078 / 0.0048 = 1.625 (docs/paper.md): held error e settles at u = 1.625 e.
TEST(PpLaw, StaticGainIsGOfOneOverFOfOne) {
  const auto p = make_params(ControllerKind::kPp);
  ControllerState s;
  ControllerOutput out;
  for (int k = 0; k < 20000; ++k) out = controller_step(p, s, 0.4, 0.0);
  EXPECT_NEAR(out.controller_v, 0.4 * 0.0078 / 0.0048, 1e-6);
}

TEST(Controller, ValveCommandSaturatesAtTheLimit) {
  const auto p = make_params(ControllerKind::kPp);
  ControllerState s;
  ControllerOutput out;
  for (int k = 0; k < 20000; ++k) out = controller_step(p, s, 8.0, 0.0);  // u -> 13 V
  EXPECT_GT(out.controller_v, 5.0);
  EXPECT_DOUBLE_EQ(out.valve_v, 5.0);
  EXPECT_TRUE(out.saturated);
}

TEST(Controller, NonFiniteInputGivesSafeCommandAndFaultAndKeepsState) {
  for (ControllerKind kind : kAllControllerKinds) {
    const auto p = make_params(kind);
    ControllerState s;
    controller_step(p, s, 1.0, 0.2);
    const ControllerState before = s;
    const auto out = controller_step(p, s, 1.0, std::numeric_limits<double>::quiet_NaN());
    EXPECT_TRUE(out.fault);
    EXPECT_EQ(out.valve_v, p.safe_valve_v());
    EXPECT_EQ(s.rst.u_past, before.rst.u_past) << to_string(kind);
    EXPECT_EQ(s.rst.y_past, before.rst.y_past) << to_string(kind);
    const auto inf = controller_step(p, s, std::numeric_limits<double>::infinity(), 0.2);
    EXPECT_TRUE(inf.fault);
  }
}

TEST(Controller, NgidzJumpsAcrossTheDeadBandAtEverySignChange) {
  const auto p = make_params(ControllerKind::kPpNgidz);
  ControllerState s;
  const auto first = controller_step(p, s, 0.5, 0.0);  // u0 = -0.0867 < 0: left branch
  EXPECT_NEAR(first.valve_v, first.controller_v / 1.0707 - 1.722, kExact);
}

TEST(Controller, FfidzUsesTheErrorSignNotTheSignOfU) {
  const auto p = make_params(ControllerKind::kPpFfidz);
  ControllerState s;
  // e = 0.5 V > l_c: DE = 1 although u0 = g0 e < 0, so the right branch is added.
  const auto out = controller_step(p, s, 0.5, 0.0);
  const double u = out.controller_v;
  ASSERT_LT(u, 0.0);
  EXPECT_NEAR(out.valve_v, u + u / 1.7627 + 1.232, kExact);
}

TEST(Controller, FfidzFeedForwardOffInsideLc) {
  const auto p = make_params(ControllerKind::kPpFfidz);
  ControllerState s;
  const auto out = controller_step(p, s, 1.0, 1.0 - 0.05);  // |e| = 0.05 V < l_c = 0.1 V
  EXPECT_NEAR(out.valve_v, out.controller_v, kExact);
}

TEST(ControllerKind, NamesRoundTripAndUnknownNameIsRefusedWithTheChoices) {
  for (ControllerKind k : kAllControllerKinds) {
    auto parsed = parse_controller_kind(to_string(k));
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, k);
  }
  EXPECT_EQ(static_cast<int>(ControllerKind::kPpFfidz), 2);  // register enumeration 0, 1, 2
  auto bad = parse_controller_kind("pid");
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("pp-ffidz"), std::string::npos);
}

// pp-traj's short approach (near a travel end) runs up to its approach speed over
// kShortApproachRunUpV, in its own sliding arrival and in the hunting fallback's alike, and never
// faster than the leg's own rate.
TEST(PpTrajParams, AShortApproachRunsUpOverItsOwnDistanceNeverFasterThanTheLeg) {
  auto c = paper_controller_config(ControllerKind::kPpTraj);
  const double v = c.trajectory.approach_speed_v_s;
  const auto p = ControllerParams::make(c);
  ASSERT_TRUE(p.has_value()) << p.error().message;
  const double run_up = v * v / (2.0 * kShortApproachRunUpV);
  ASSERT_LT(run_up, p->trajectory().approach.accel_v_s2) << "the case does not test the run-up";
  EXPECT_DOUBLE_EQ(p->trajectory().approach.short_approach_accel_v_s2, run_up);
  EXPECT_DOUBLE_EQ(p->trajectory().fallback_approach.short_approach_accel_v_s2, run_up);

  c.trajectory.accel_v_s2 = 0.5 * run_up;  // a leg slower than the run-up
  const auto slow = ControllerParams::make(c);
  ASSERT_TRUE(slow.has_value()) << slow.error().message;
  EXPECT_DOUBLE_EQ(slow->trajectory().approach.short_approach_accel_v_s2, 0.5 * run_up);
}

}  // namespace
}  // namespace epa::control
