#include "control/dead_zone_compensation.hpp"

#include <gtest/gtest.h>

#include "core/paper_reference.hpp"

namespace epa::control {
namespace {

constexpr double kTol = 1e-12;
const core::DeadZone kDz = core::paper::model().dead_zone;

// (1 + 1/m*) u + b* through the dead zone gives (1 + m*) u: the branch gain of eq 14/15 (docs/paper.md).
TEST(FfidzCompensation, ThroughTheDeadZoneGivesOnePlusSlopeTimesU) {
  for (double u : {0.05, 0.3, 1.0, 2.0}) {
    EXPECT_NEAR(kDz.apply(ffidz_command(kDz, u, /*e=*/1.0, /*lc=*/0.1)), (1.0 + kDz.m_r) * u, kTol) << u;
    EXPECT_NEAR(kDz.apply(ffidz_command(kDz, -u, /*e=*/-1.0, /*lc=*/0.1)), (1.0 + kDz.m_l) * -u, kTol) << u;
  }
}

TEST(NgidzCompensation, ThroughTheDeadZoneGivesUExactly) {
  for (double u : {-3.0, -0.2, -1e-6, 1e-6, 0.2, 3.0}) EXPECT_NEAR(kDz.apply(ngidz_command(kDz, u)), u, kTol) << u;
  EXPECT_EQ(ngidz_command(kDz, 0.0), 0.0);
}

TEST(FfidzCompensation, AtExactlyLcTheFeedForwardIsOff) {
  EXPECT_EQ(ffidz_command(kDz, 0.3, 0.1, 0.1), 0.3);   // l_c = 1 only when |e| > l_c
  EXPECT_EQ(ffidz_command(kDz, 0.3, -0.1, 0.1), 0.3);
}

TEST(FfidzCompensation, NegativeErrorUsesTheLeftBranch) {
  EXPECT_NEAR(ffidz_command(kDz, 0.2, -0.5, 0.1), 0.2 + 0.2 / kDz.m_l + kDz.b_l, kTol);
}

}  // namespace
}  // namespace epa::control
