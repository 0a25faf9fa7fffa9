#include "control/pole_placement_design.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "control/diophantine.hpp"
#include "core/paper_reference.hpp"

namespace epa::control {
namespace {

constexpr double kThreeDecimals = 5e-4;  // "reproduce eq 14 and 15 to 3 decimals"

TEST(PaperBranches, LeftAndRightReproduceEq14And15ToThreeDecimals) {
  const auto branches = analyse_branches(core::paper::model(), core::paper::F(), core::paper::G());
  ASSERT_EQ(branches.size(), 3u);
  EXPECT_EQ(branches[1].name, "left");
  EXPECT_EQ(branches[2].name, "right");
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_NEAR(branches[1].P[i], core::paper::kEq14[i], kThreeDecimals) << "eq 14 coefficient " << i;
    EXPECT_NEAR(branches[2].P[i], core::paper::kEq15[i], kThreeDecimals) << "eq 15 coefficient " << i;
  }
}

TEST(PaperBranches, AllBranchesAreStableByJuryWithLargestRootNearPointNineSeven) {
  for (const auto& b : analyse_branches(core::paper::model(), core::paper::F(), core::paper::G())) {
    EXPECT_EQ(b.jury.verdict, Stability::kStable) << b.name;
    EXPECT_LT(b.max_root_abs, 0.985) << b.name;  // docs/paper.md: about 0.974 for left/right
    EXPECT_GT(b.max_root_abs, 0.96) << b.name;
  }
}

TEST(PaperBranches, GainsAreOnePlusSlope) {
  const auto b = analyse_branches(core::paper::model(), core::paper::F(), core::paper::G());
  EXPECT_DOUBLE_EQ(b[0].gain, 1.0);
  EXPECT_DOUBLE_EQ(b[1].gain, 1.0 + 1.0707);
  EXPECT_DOUBLE_EQ(b[2].gain, 1.0 + 1.7627);
}

// docs/paper.md: with the exact solution of eq 4 the loop has a root at z = 1 (T(1) = 0).
TEST(PaperBranches, ExactlySolvedControllerIsMarginalNotStable) {
  const auto m = core::paper::model();
  auto sol = solve_diophantine(m.A, m.B, core::paper::T());
  ASSERT_TRUE(sol.has_value());
  const auto branches = analyse_branches(m, sol->F, sol->G);
  EXPECT_EQ(branches[0].jury.verdict, Stability::kMarginal);
  EXPECT_NEAR(branches[0].max_root_abs, 1.0, 1e-9);
}

// 0 % overshoot -> zeta = 1 (double real pole); r = exp(-4 Ts / settling).
TEST(SpecDesign, CriticallyDampedPairForZeroOvershoot) {
  auto T = characteristic_from_spec({.overshoot_pct = 0.0, .settling_s = 2.0, .Ts = 0.01, .observer_pole = 0.0}, 2);
  ASSERT_TRUE(T.has_value());
  const double r = std::exp(-4.0 * 0.01 / 2.0);
  EXPECT_NEAR((*T)[1], -2.0 * r, 1e-12);
  EXPECT_NEAR((*T)[2], r * r, 1e-12);
}

// OS = 2 %: zeta = -ln(0.02)/sqrt(pi^2 + ln(0.02)^2) = 0.7797; the pair has |z| = exp(-sigma Ts)
// and angle wd Ts with wd = sigma sqrt(1 - zeta^2) / zeta.
TEST(SpecDesign, DominantPairHasTheSpecifiedDecayAndDamping) {
  const double Ts = 0.01, settling = 2.0;
  auto T = characteristic_from_spec({.overshoot_pct = 2.0, .settling_s = settling, .Ts = Ts, .observer_pole = 0.3}, 5);
  ASSERT_TRUE(T.has_value());
  EXPECT_EQ(T->degree(), 5);
  const double sigma = 4.0 / settling, zeta = 0.779696;
  const double wd = sigma * std::sqrt(1 - zeta * zeta) / zeta;
  int pair_roots = 0, observer_roots = 0;
  for (const auto& z : T->z_roots()) {
    if (std::abs(z - std::complex<double>(0.3, 0.0)) < 1e-4) ++observer_roots;
    else if (std::abs(std::abs(z) - std::exp(-sigma * Ts)) < 1e-9 && std::abs(std::abs(std::arg(z)) - wd * Ts) < 1e-5) ++pair_roots;
  }
  EXPECT_EQ(pair_roots, 2);
  EXPECT_EQ(observer_roots, 3);
}

TEST(SpecDesign, DesignedControllerPlacesThePolesOnThePaperModel) {
  const auto m = core::paper::model();
  auto T = characteristic_from_spec({.overshoot_pct = 5.0, .settling_s = 0.5, .Ts = m.Ts, .observer_pole = 0.5}, 5);
  ASSERT_TRUE(T.has_value());
  auto sol = solve_diophantine(m.A, m.B, *T);
  ASSERT_TRUE(sol.has_value());
  const auto nominal = analyse_branches(m, sol->F, sol->G)[0];
  EXPECT_EQ(nominal.jury.verdict, Stability::kStable);
  for (std::size_t i = 0; i < T->size(); ++i) EXPECT_NEAR(nominal.P[i], (*T)[i], 1e-9);
}

TEST(SpecDesign, OutOfRangeFieldsAreNamed) {
  auto bad = characteristic_from_spec({.overshoot_pct = 120.0, .settling_s = 2.0, .Ts = 0.01, .observer_pole = 0.0}, 3);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("overshoot"), std::string::npos);
  bad = characteristic_from_spec({.overshoot_pct = 2.0, .settling_s = -1.0, .Ts = 0.01, .observer_pole = 0.0}, 3);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("settling"), std::string::npos);
  bad = characteristic_from_spec({.overshoot_pct = 2.0, .settling_s = 1.0, .Ts = 0.01, .observer_pole = 1.0}, 3);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("observer"), std::string::npos);
}

}  // namespace
}  // namespace epa::control
