#include "core/dead_zone.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "../support/text_contains.hpp"

namespace epa::core {
namespace {

// apply() and inverse() are one multiply and one add each; composing them loses at most a few
// ulps of the break point (about 2 V), so 1e-12 V is loose by three orders of magnitude.
constexpr double kTolV = 1e-12;

// Paper eq 10 (m_l = 1.0707, docs/paper.md).
constexpr DeadZone kPaper{.m_r = 1.7627, .m_l = 1.0707, .b_r = 1.232, .b_l = -1.722};

using epa::test::contains;

TEST(DeadZone, ApplyInsideTheBandIsZero) {
  for (double u : {-1.7, -1.0, -0.5, 0.0, 0.3, 1.0, 1.23}) EXPECT_EQ(kPaper.apply(u), 0.0) << "u = " << u;
}

TEST(DeadZone, ApplyAtExactlyTheBreakPointsIsZero) {
  EXPECT_EQ(kPaper.apply(kPaper.b_r), 0.0);
  EXPECT_EQ(kPaper.apply(kPaper.b_l), 0.0);
}

TEST(DeadZone, ApplyAboveRightBreakPointHasSlopeMr) {
  // m_r (u - b_r): 1 V past b_r gives m_r; 5 V input gives 1.7627 * 3.768 = 6.6418536.
  EXPECT_NEAR(kPaper.apply(kPaper.b_r + 1.0), 1.7627, kTolV);
  EXPECT_NEAR(kPaper.apply(5.0), 6.6418536, kTolV);
  EXPECT_NEAR(kPaper.apply(4.0) - kPaper.apply(3.0), 1.7627, kTolV);
  EXPECT_GT(kPaper.apply(1.2321), 0.0);
}

TEST(DeadZone, ApplyBelowLeftBreakPointHasSlopeMl) {
  // m_l (u - b_l): 1 V below b_l gives -m_l; -5 V input gives 1.0707 * (-3.278) = -3.5097546.
  EXPECT_NEAR(kPaper.apply(kPaper.b_l - 1.0), -1.0707, kTolV);
  EXPECT_NEAR(kPaper.apply(-5.0), -3.5097546, kTolV);
  EXPECT_NEAR(kPaper.apply(-3.0) - kPaper.apply(-4.0), 1.0707, kTolV);
  EXPECT_LT(kPaper.apply(-1.7221), 0.0);
}

TEST(DeadZone, DefaultIsTheIdentity) {
  const DeadZone identity;
  for (double u : {-3.0, -0.25, 0.0, 0.25, 3.0}) {
    EXPECT_EQ(identity.apply(u), u);
    EXPECT_EQ(identity.inverse(u), u);
  }
}

TEST(DeadZone, InverseOfZeroIsZero) {
  EXPECT_EQ(kPaper.inverse(0.0), 0.0);
  EXPECT_EQ(kPaper.inverse(-0.0), 0.0);
}

TEST(DeadZone, InverseFollowsEq5OnEachSide) {
  // u_d / m_r + b_r for u_d > 0; u_d / m_l + b_l for u_d < 0.
  EXPECT_NEAR(kPaper.inverse(1.7627), 1.0 + 1.232, kTolV);
  EXPECT_NEAR(kPaper.inverse(-1.0707), -1.0 - 1.722, kTolV);
  EXPECT_GT(kPaper.inverse(1e-6), kPaper.b_r);  // the smallest push already jumps the gap
  EXPECT_LT(kPaper.inverse(-1e-6), kPaper.b_l);
}

TEST(DeadZone, ApplyOfInverseIsIdentityForNonZeroDemands) {
  for (int i = 1; i <= 400; ++i) {
    const double ud = 0.025 * i;  // 0.025 .. 10
    EXPECT_NEAR(kPaper.apply(kPaper.inverse(ud)), ud, kTolV) << "u_d = " << ud;
    EXPECT_NEAR(kPaper.apply(kPaper.inverse(-ud)), -ud, kTolV) << "u_d = " << -ud;
  }
  for (double ud : {1e-3, 1e-6, 123.456}) {
    EXPECT_NEAR(kPaper.apply(kPaper.inverse(ud)), ud, kTolV);
    EXPECT_NEAR(kPaper.apply(kPaper.inverse(-ud)), -ud, kTolV);
  }
}

TEST(DeadZone, InverseOfApplyIsIdentityOutsideTheBand) {
  for (int i = 1; i <= 400; ++i) {
    const double step = 0.02 * i;  // 0.02 .. 8 V beyond each break point
    const double right = kPaper.b_r + step, left = kPaper.b_l - step;
    EXPECT_NEAR(kPaper.inverse(kPaper.apply(right)), right, kTolV) << "u = " << right;
    EXPECT_NEAR(kPaper.inverse(kPaper.apply(left)), left, kTolV) << "u = " << left;
  }
}

TEST(DeadZone, InverseOfApplyCollapsesTheBandToZero) {
  // Inside the band apply() gives 0 and inverse(0) is 0: the band is not invertible.
  EXPECT_EQ(kPaper.inverse(kPaper.apply(1.0)), 0.0);
  EXPECT_EQ(kPaper.inverse(kPaper.apply(-1.0)), 0.0);
}

TEST(DeadZone, PaperDeadZoneIsValid) {
  const Status s = kPaper.validate();
  EXPECT_TRUE(s.has_value()) << (s ? "" : s.error().message);
}

TEST(DeadZone, ValidateRefusesNonPositiveRightSlopeNamingMr) {
  DeadZone dz = kPaper;
  dz.m_r = 0.0;
  const Status s = dz.validate();
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_TRUE(contains(s.error().message, "m_r"));
  EXPECT_FALSE(contains(s.error().message, "m_l"));
  dz.m_r = -1.0;
  ASSERT_FALSE(dz.validate().has_value());
  EXPECT_TRUE(contains(dz.validate().error().message, "m_r"));
}

TEST(DeadZone, ValidateRefusesNonPositiveLeftSlopeNamingMl) {
  DeadZone dz = kPaper;
  dz.m_l = -1.0707;
  const Status s = dz.validate();
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_TRUE(contains(s.error().message, "m_l"));
  EXPECT_FALSE(contains(s.error().message, "m_r"));
}

TEST(DeadZone, ValidateRefusesLeftBreakPointAboveRightNamingBl) {
  DeadZone dz = kPaper;
  dz.b_l = 1.5;  // > b_r = 1.232
  const Status s = dz.validate();
  ASSERT_FALSE(s.has_value());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_TRUE(contains(s.error().message, "b_l"));
}

TEST(DeadZone, ValidateAcceptsEqualBreakPoints) {
  DeadZone dz = kPaper;
  dz.b_l = dz.b_r = 0.4;
  const Status s = dz.validate();
  EXPECT_TRUE(s.has_value()) << (s ? "" : s.error().message);
  // A zero-width band: only u = b exactly gives 0, with the two slopes on either side.
  EXPECT_EQ(dz.apply(0.4), 0.0);
  EXPECT_NEAR(dz.apply(1.4), 1.7627, kTolV);
  EXPECT_NEAR(dz.apply(-0.6), -1.0707, kTolV);
}

TEST(DeadZone, ValidateRefusesNaNSayingFinite) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  {
    DeadZone dz = kPaper;
    dz.m_r = nan;
    const Status s = dz.validate();
    ASSERT_FALSE(s.has_value());
    EXPECT_TRUE(contains(s.error().message, "finite"));
    EXPECT_TRUE(contains(s.error().message, "m_r"));
  }
  {
    DeadZone dz = kPaper;
    dz.b_l = nan;  // NaN compares false with everything, so only an explicit check catches it
    const Status s = dz.validate();
    ASSERT_FALSE(s.has_value());
    EXPECT_TRUE(contains(s.error().message, "finite"));
    EXPECT_TRUE(contains(s.error().message, "b_l"));
  }
}

TEST(DeadZone, ValidateRefusesInfinitySayingFinite) {
  DeadZone dz = kPaper;
  dz.b_r = std::numeric_limits<double>::infinity();
  const Status s = dz.validate();
  ASSERT_FALSE(s.has_value());
  EXPECT_TRUE(contains(s.error().message, "finite"));
  EXPECT_TRUE(contains(s.error().message, "b_r"));
}

}  // namespace
}  // namespace epa::core
