#include "control/jury.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/paper_reference.hpp"
#include "core/polynomial.hpp"
#include "core/random.hpp"

namespace epa::control {
namespace {

// Table entries are products of two or three short decimals: a few ulps of error.
constexpr double kTableTol = 1e-12;
// Random polynomials whose largest root is this close to the unit circle are left out of the
// cross-check: their verdict depends on rounding (and on the Jury tolerance), not on the test.
constexpr double kNearCircle = 1e-6;

using Coeffs = std::vector<double>;

// Product of descending-power polynomials (a convolution of the coefficient lists).
Coeffs multiply(const Coeffs& a, const Coeffs& b) {
  Coeffs r(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) r[i + j] += a[i] * b[j];
  return r;
}

// (z - r) and (z - w)(z - conj w) = z^2 - 2 Re(w) z + |w|^2, descending powers.
Coeffs real_root(double r) { return {1.0, -r}; }
Coeffs complex_pair(double radius, double angle) {
  return {1.0, -2.0 * radius * std::cos(angle), radius * radius};
}

Stability verdict(const Coeffs& p) { return jury_test(p).verdict; }

TEST(Jury, ProductOfTwoInsideRealFactorsIsStable) {
  // (z - 0.5)(z + 0.3) = z^2 - 0.2z - 0.15
  EXPECT_EQ(verdict({1.0, -0.2, -0.15}), Stability::kStable);
}

TEST(Jury, LightlyDampedComplexPairInsideIsStable) {
  // z^2 - 1.8z + 0.9: roots 0.9 +- 0.3i, |z| = sqrt(0.9) = 0.949
  EXPECT_EQ(verdict({1.0, -1.8, 0.9}), Stability::kStable);
}

TEST(Jury, DegreeFiveWithAllRootsInsideIsStable) {
  // (z - 0.5)(z + 0.4)(z - 0.3)(z^2 - z + 0.5): the pair is 0.5 +- 0.5i, |z| = 0.707
  const Coeffs p = multiply(multiply(multiply(real_root(0.5), real_root(-0.4)), real_root(0.3)), {1.0, -1.0, 0.5});
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(verdict(p), Stability::kStable);
}

TEST(Jury, FirstOrderVerdictFollowsTheSingleRoot) {
  EXPECT_EQ(verdict({1.0, -0.5}), Stability::kStable);    // z = 0.5
  EXPECT_EQ(verdict({1.0, 0.99}), Stability::kStable);    // z = -0.99
  EXPECT_EQ(verdict({1.0, 1.5}), Stability::kUnstable);   // z = -1.5
  EXPECT_EQ(verdict({1.0, -1.0}), Stability::kMarginal);  // z = 1
}

TEST(Jury, MarginalPolynomialWithRootAtOneIsMarginalNotStable) {
  // (z - 1)(z - 0.5) = z^2 - 1.5z + 0.5: P(1) = 0
  EXPECT_EQ(verdict({1.0, -1.5, 0.5}), Stability::kMarginal);
}

TEST(Jury, RootAtMinusOneIsMarginal) {
  // (z + 1)(z - 0.5) = z^2 + 0.5z - 0.5: P(-1) = 1 - 0.5 - 0.5 = 0
  EXPECT_EQ(verdict({1.0, 0.5, -0.5}), Stability::kMarginal);
}

TEST(Jury, ComplexPairOnTheUnitCircleIsMarginal) {
  // z^2 + 1: roots +-i. P(1) = P(-1) = 2 > 0, but |a0| = |a2| = 1.
  EXPECT_EQ(verdict({1.0, 0.0, 1.0}), Stability::kMarginal);
  EXPECT_EQ(verdict(complex_pair(1.0, 1.0)), Stability::kMarginal);  // e^{+-i}
}

TEST(Jury, UnitCirclePairFoundAtADeeperReductionLevelIsMarginal) {
  // (z^2 + 1)(z - 0.5)(z + 0.2) = z^4 - 0.3z^3 + 0.9z^2 - 0.3z - 0.1.
  // By hand: |a0| = 1 > 0.1; b = [0.99, -0.33, 0.99, -0.33], |b0| > |b3|;
  // c = [0.99^2 - 0.33^2, 0, same] = [0.8712, 0, 0.8712]: |c0| = |c2|, the boundary.
  const Coeffs p = {1.0, -0.3, 0.9, -0.3, -0.1};
  const JuryResult r = jury_test(p);
  EXPECT_EQ(r.verdict, Stability::kMarginal);
  ASSERT_GE(r.table.size(), 5u);
  ASSERT_EQ(r.table[2].size(), 4u);
  EXPECT_NEAR(r.table[2][0], 0.99, kTableTol);
  EXPECT_NEAR(r.table[2][1], -0.33, kTableTol);
  EXPECT_NEAR(r.table[2][2], 0.99, kTableTol);
  EXPECT_NEAR(r.table[2][3], -0.33, kTableTol);
  ASSERT_EQ(r.table[4].size(), 3u);
  EXPECT_NEAR(r.table[4][0], 0.8712, kTableTol);
  EXPECT_NEAR(r.table[4][1], 0.0, kTableTol);
  EXPECT_NEAR(r.table[4][2], 0.8712, kTableTol);
}

TEST(Jury, RealRootOutsideAtPlusOnePointTwoIsUnstable) {
  // (z - 1.2)(z - 0.5) = z^2 - 1.7z + 0.6: P(1) = -0.1
  EXPECT_EQ(verdict({1.0, -1.7, 0.6}), Stability::kUnstable);
}

TEST(Jury, RealRootOutsideAtMinusOnePointOneIsUnstable) {
  // (z + 1.1)(z - 0.3) = z^2 + 0.8z - 0.33: P(-1) = 1 - 0.8 - 0.33 = -0.13
  EXPECT_EQ(verdict({1.0, 0.8, -0.33}), Stability::kUnstable);
}

TEST(Jury, ComplexPairJustOutsideIsUnstable) {
  // |z| = 1.05 at +-60 degrees: z^2 - 1.05z + 1.1025; P(+-1) > 0 but |a2| = 1.1025 > |a0| = 1.
  EXPECT_EQ(verdict({1.0, -1.05, 1.1025}), Stability::kUnstable);
  EXPECT_EQ(verdict(complex_pair(1.05, std::numbers::pi / 3.0)), Stability::kUnstable);
}

TEST(Jury, RootOnTheCircleAndRootOutsideIsUnstableNotMarginal) {
  // (z - 1)(z - 2) = z^2 - 3z + 2: P(1) = 0 (boundary) but |a2| = 2 > |a0| = 1 fails outright.
  EXPECT_EQ(verdict({1.0, -3.0, 2.0}), Stability::kUnstable);
}

TEST(Jury, NegativeLeadingCoefficientIsNormalised) {
  // -(z - 0.5)(z + 0.3): same roots, so the same verdict.
  const JuryResult r = jury_test({-1.0, 0.2, 0.15});
  EXPECT_EQ(r.verdict, Stability::kStable);
  ASSERT_FALSE(r.table.empty());
  EXPECT_EQ(r.table[0], (Coeffs{1.0, -0.2, -0.15}));
  ASSERT_FALSE(r.conditions.empty());
  EXPECT_NEAR(r.conditions[0].lhs, 0.65, kTableTol);  // P(1) of the normalised polynomial
  EXPECT_EQ(verdict({-1.0, 1.7, -0.6}), Stability::kUnstable);  // -(z - 1.2)(z - 0.5)
}

TEST(Jury, LeadingZerosAreDropped) {
  const JuryResult r = jury_test({0.0, 0.0, 1.0, -0.2, -0.15});
  EXPECT_EQ(r.verdict, Stability::kStable);
  ASSERT_FALSE(r.table.empty());
  EXPECT_EQ(r.table[0], (Coeffs{1.0, -0.2, -0.15}));
  ASSERT_FALSE(r.conditions.empty());
  EXPECT_EQ(r.conditions[1].text, "(-1)^2 P(-1) > 0");  // degree 2, not 4
}

TEST(Jury, ScalingThePolynomialDoesNotChangeTheVerdict) {
  EXPECT_EQ(verdict({1000.0, -200.0, -150.0}), Stability::kStable);
  EXPECT_EQ(verdict({1e-3, -1.5e-3, 0.5e-3}), Stability::kMarginal);
  EXPECT_EQ(verdict({1e-3, -1.7e-3, 0.6e-3}), Stability::kUnstable);
}

TEST(Jury, TableStartsWithTheInputAndItsReverse) {
  const JuryResult r = jury_test({1.0, -0.2, -0.15});
  // Reduction b_k = a0 a_k - a2 a_{2-k}:
  //   b0 = 1 * 1 - (-0.15)(-0.15) = 0.9775, b1 = 1 * (-0.2) - (-0.15)(-0.2) = -0.23.
  ASSERT_EQ(r.table.size(), 4u);
  EXPECT_EQ(r.table[0], (Coeffs{1.0, -0.2, -0.15}));
  EXPECT_EQ(r.table[1], (Coeffs{-0.15, -0.2, 1.0}));
  ASSERT_EQ(r.table[2].size(), 2u);
  EXPECT_NEAR(r.table[2][0], 0.9775, kTableTol);
  EXPECT_NEAR(r.table[2][1], -0.23, kTableTol);
  ASSERT_EQ(r.table[3].size(), 2u);
  EXPECT_NEAR(r.table[3][0], -0.23, kTableTol);
  EXPECT_NEAR(r.table[3][1], 0.9775, kTableTol);
}

TEST(Jury, ConditionsStartWithPOfOne) {
  const JuryResult r = jury_test({1.0, -0.2, -0.15});
  ASSERT_EQ(r.conditions.size(), 4u);  // P(1), P(-1), |a0| > |a2|, |b0| > |b1|
  EXPECT_EQ(r.conditions[0].text, "P(1) > 0");
  EXPECT_NEAR(r.conditions[0].lhs, 0.65, kTableTol);  // 1 - 0.2 - 0.15
  EXPECT_EQ(r.conditions[0].rhs, 0.0);
  EXPECT_TRUE(r.conditions[0].holds);
  EXPECT_EQ(r.conditions[1].text, "(-1)^2 P(-1) > 0");
  EXPECT_NEAR(r.conditions[1].lhs, 1.05, kTableTol);  // 1 + 0.2 - 0.15
  EXPECT_EQ(r.conditions[2].text, "|a0| > |a2|");
  EXPECT_NEAR(r.conditions[2].lhs, 1.0, kTableTol);
  EXPECT_NEAR(r.conditions[2].rhs, 0.15, kTableTol);
  EXPECT_EQ(r.conditions[3].text, "|b0| > |b1|");
  EXPECT_NEAR(r.conditions[3].lhs, 0.9775, kTableTol);
  EXPECT_NEAR(r.conditions[3].rhs, 0.23, kTableTol);
  for (const auto& c : r.conditions) {
    EXPECT_TRUE(c.holds) << c.text;
    EXPECT_FALSE(c.boundary) << c.text;
  }
}

TEST(Jury, FailedConditionIsReportedAndBoundaryIsFlagged) {
  const JuryResult unstable = jury_test({1.0, -1.7, 0.6});  // P(1) = -0.1
  ASSERT_FALSE(unstable.conditions.empty());
  EXPECT_FALSE(unstable.conditions[0].holds);
  EXPECT_FALSE(unstable.conditions[0].boundary);
  EXPECT_NEAR(unstable.conditions[0].lhs, -0.1, kTableTol);

  const JuryResult marginal = jury_test({1.0, -1.5, 0.5});  // P(1) = 0
  ASSERT_FALSE(marginal.conditions.empty());
  EXPECT_FALSE(marginal.conditions[0].holds);
  EXPECT_TRUE(marginal.conditions[0].boundary);
}

TEST(Jury, VerdictNamesAreReadable) {
  EXPECT_STREQ(to_string(Stability::kStable), "stable");
  EXPECT_STREQ(to_string(Stability::kMarginal), "marginal");
  EXPECT_STREQ(to_string(Stability::kUnstable), "unstable");
}

TEST(Jury, PaperClosedLoopsOfEq14And15AreStable) {
  // docs/paper.md: both loops are stable, largest root about 0.974.
  for (const auto& eq : {core::paper::kEq14, core::paper::kEq15}) {
    const Coeffs p(eq.begin(), eq.end());
    EXPECT_EQ(verdict(p), Stability::kStable);
    EXPECT_LT(core::Polynomial(p).max_root_abs(), 1.0);
  }
}

TEST(Jury, PaperTAndAAreMarginalAndBZerosAreOutside) {
  // T = (1 - q)(1 - 1.865q + 0.8694q^2) and A = (1 - q)(...): a root at z = 1 each (docs/paper.md).
  EXPECT_EQ(verdict(core::paper::T().coefficients()), Stability::kMarginal);
  EXPECT_EQ(verdict(core::paper::model().A.coefficients()), Stability::kMarginal);
  // B's zeros: 1.024z^2 - 2.046z + 1.029 (leading 0 dropped), |z|^2 = 1.029 / 1.024 > 1.
  EXPECT_EQ(verdict(core::paper::model().B.coefficients()), Stability::kUnstable);
}

TEST(Jury, AgreesWithLargestRootOnRandomPolynomials) {
  core::Random rng(20240611);
  int stable = 0, unstable = 0, checked = 0, attempts = 0;
  while (checked < 300 && attempts < 2000) {
    ++attempts;
    // Degree 1..6 built from random roots of radius up to 1.4 (real ones and conjugate pairs)
    // and a random gain of either sign, so both verdicts are common.
    const int degree = 1 + static_cast<int>(rng.uniform() * 6.0);
    Coeffs p = {0.5 + 2.5 * rng.uniform()};
    if (rng.uniform() < 0.5) p[0] = -p[0];
    int remaining = degree;
    while (remaining > 0) {
      const double radius = 1.4 * rng.uniform();
      if (remaining >= 2 && rng.uniform() < 0.5) {
        p = multiply(p, complex_pair(radius, std::numbers::pi * rng.uniform()));
        remaining -= 2;
      } else {
        p = multiply(p, real_root(rng.uniform() < 0.5 ? radius : -radius));
        remaining -= 1;
      }
    }
    ASSERT_EQ(p.size(), static_cast<std::size_t>(degree) + 1);
    const double max_root = core::Polynomial(p).max_root_abs();
    double max_root_desc = 0.0;
    for (const auto& z : core::roots_descending(p)) max_root_desc = std::max(max_root_desc, std::abs(z));
    ASSERT_DOUBLE_EQ(max_root, max_root_desc);  // the same roots, two entry points
    if (std::abs(max_root - 1.0) < kNearCircle) continue;
    ++checked;
    const Stability expected = max_root < 1.0 ? Stability::kStable : Stability::kUnstable;
    (expected == Stability::kStable ? stable : unstable)++;
    std::ostringstream poly;
    for (double c : p) poly << c << ' ';
    EXPECT_EQ(verdict(p), expected) << "max |root| = " << max_root << ", p = " << poly.str();
  }
  EXPECT_GE(checked, 200);
  // Both outcomes must be well represented, or the cross-check proves little.
  EXPECT_GE(stable, 50);
  EXPECT_GE(unstable, 50);
}

}  // namespace
}  // namespace epa::control
