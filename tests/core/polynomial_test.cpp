#include "core/polynomial.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

namespace epa::core {
namespace {

// Arithmetic on short lists of decimals: each result is a handful of roundings of values near 1.
constexpr double kArithTol = 1e-12;
// Roots come from a companion-matrix eigenvalue solver (a backward-stable algorithm): for the
// well-separated simple roots used here, the error is a few hundred ulps at most.
constexpr double kRootTol = 1e-9;

void expect_coefficients(const Polynomial& p, const std::vector<double>& expected, double tol = kArithTol) {
  ASSERT_EQ(p.size(), expected.size()) << p.to_string();
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(p[i], expected[i], tol) << "coefficient " << i;
}

// True when some root lies within tol of `z` (order of the roots is not part of the contract).
::testing::AssertionResult has_root(const std::vector<std::complex<double>>& roots, std::complex<double> z,
                                    double tol = kRootTol) {
  for (const auto& r : roots)
    if (std::abs(r - z) <= tol) return ::testing::AssertionSuccess();
  auto failure = ::testing::AssertionFailure() << "no root near " << z << "; roots:";
  for (const auto& r : roots) failure << ' ' << r;
  return failure;
}

// The paper's model (eq 9) and desired polynomial (eq 11), q = z^-1.
const Polynomial kPaperA{1.0, -0.9094, -0.6110, 0.5204};
const Polynomial kPaperB{0.0, 1.024, -2.046, 1.029};
const Polynomial kPaperT{1.0, -2.865, 2.7344, -0.8694};

TEST(Polynomial, MultiplyIsConvolutionOfCoefficients) {
  // (1 - 0.5q)(1 + 0.3q) = 1 + (0.3 - 0.5) q - 0.15 q^2
  expect_coefficients(Polynomial{1.0, -0.5} * Polynomial{1.0, 0.3}, {1.0, -0.2, -0.15});
  // (1 + 2q + 3q^2)(4 + 5q) = 4 + 13q + 22q^2 + 15q^3
  expect_coefficients(Polynomial{1.0, 2.0, 3.0} * Polynomial{4.0, 5.0}, {4.0, 13.0, 22.0, 15.0});
}

TEST(Polynomial, MultiplyByEmptyPolynomialIsEmpty) {
  EXPECT_EQ((Polynomial{} * Polynomial{1.0, 2.0}).size(), 0u);
  EXPECT_EQ((Polynomial{1.0, 2.0} * Polynomial{}).size(), 0u);
}

TEST(Polynomial, AddPadsTheShorterOperandWithZeros) {
  expect_coefficients(Polynomial{1.0, 2.0} + Polynomial{3.0, 4.0, 5.0}, {4.0, 6.0, 5.0});
  expect_coefficients(Polynomial{3.0, 4.0, 5.0} + Polynomial{1.0, 2.0}, {4.0, 6.0, 5.0});
}

TEST(Polynomial, SubtractPadsTheShorterOperandWithZeros) {
  expect_coefficients(Polynomial{1.0, 2.0} - Polynomial{3.0, 4.0, 5.0}, {-2.0, -2.0, -5.0});
  expect_coefficients(Polynomial{3.0, 4.0, 5.0} - Polynomial{1.0, 2.0}, {2.0, 2.0, 5.0});
}

TEST(Polynomial, ScaleMultipliesEveryCoefficient) {
  expect_coefficients(Polynomial{1.0, -2.0, 3.0} * 2.0, {2.0, -4.0, 6.0});
  expect_coefficients(Polynomial{1.0, -2.0, 3.0} * -0.5, {-0.5, 1.0, -1.5});
}

TEST(Polynomial, IndexBeyondTheEndReadsZero) {
  const Polynomial p{1.0, 2.0};
  EXPECT_EQ(p[0], 1.0);
  EXPECT_EQ(p[1], 2.0);
  EXPECT_EQ(p[2], 0.0);
  EXPECT_EQ(p[100], 0.0);
}

TEST(Polynomial, DegreeIgnoresTrailingZeroCoefficients) {
  EXPECT_EQ((Polynomial{1.0, -0.5, 0.25}).degree(), 2);
  EXPECT_EQ((Polynomial{1.0, 0.0, 0.0}).degree(), 0);
  EXPECT_EQ((Polynomial{0.0, 0.0, 3.0}).degree(), 2);
  EXPECT_EQ(kPaperB.degree(), 3);
}

TEST(Polynomial, DegreeOfZeroPolynomialIsMinusOne) {
  EXPECT_EQ(Polynomial{}.degree(), -1);
  EXPECT_EQ((Polynomial{0.0}).degree(), -1);
  EXPECT_EQ((Polynomial{0.0, 0.0}).degree(), -1);
}

TEST(Polynomial, EvaluatesAtRealQ) {
  const Polynomial p{1.0, 2.0, 3.0};
  EXPECT_DOUBLE_EQ(p.at(0.0), 1.0);
  EXPECT_DOUBLE_EQ(p.at(2.0), 17.0);   // 1 + 4 + 12
  EXPECT_DOUBLE_EQ(p.at(-1.0), 2.0);   // 1 - 2 + 3
  EXPECT_DOUBLE_EQ(p.at(0.5), 2.75);   // 1 + 1 + 0.75
  EXPECT_EQ(Polynomial{}.at(3.0), 0.0);
}

TEST(Polynomial, EvaluatesAtComplexQ) {
  const Polynomial p{1.0, 2.0, 3.0};
  // q = i: 1 + 2i + 3 i^2 = -2 + 2i
  const std::complex<double> v = p.at(std::complex<double>(0.0, 1.0));
  EXPECT_NEAR(v.real(), -2.0, kArithTol);
  EXPECT_NEAR(v.imag(), 2.0, kArithTol);
  // q = 1 + i: q^2 = 2i, so 1 + 2 + 2i + 6i = 3 + 8i
  const std::complex<double> w = p.at(std::complex<double>(1.0, 1.0));
  EXPECT_NEAR(w.real(), 3.0, kArithTol);
  EXPECT_NEAR(w.imag(), 8.0, kArithTol);
}

TEST(Polynomial, ComplexEvaluationAtRealQMatchesRealEvaluation) {
  const std::complex<double> v = kPaperA.at(std::complex<double>(0.7, 0.0));
  EXPECT_NEAR(v.real(), kPaperA.at(0.7), kArithTol);
  EXPECT_NEAR(v.imag(), 0.0, kArithTol);
}

TEST(Polynomial, DescendingZWithItsOwnDegreeIsTheSameList) {
  const std::vector<double> d = kPaperT.descending_z(3);
  EXPECT_EQ(d, kPaperT.coefficients());
}

TEST(Polynomial, DescendingZPadsWithZerosForAHigherDegree) {
  // z^3 (1 - 0.5 z^-1) = z^3 - 0.5 z^2 + 0 z + 0
  const std::vector<double> d = Polynomial{1.0, -0.5}.descending_z(3);
  EXPECT_EQ(d, (std::vector<double>{1.0, -0.5, 0.0, 0.0}));
}

TEST(Polynomial, ZRootsOfProductOfTwoRealFactors) {
  // (1 - 0.5q)(1 + 0.3q): z^2 - 0.2 z - 0.15 = (z - 0.5)(z + 0.3)
  const auto roots = (Polynomial{1.0, -0.5} * Polynomial{1.0, 0.3}).z_roots();
  ASSERT_EQ(roots.size(), 2u);
  EXPECT_TRUE(has_root(roots, 0.5));
  EXPECT_TRUE(has_root(roots, -0.3));
}

TEST(Polynomial, ZRootsOfComplexPairAreConjugates) {
  // z^2 - 1.2 z + 0.72: roots 0.6 +- 0.6i (sum 1.2, product 0.36 + 0.36 = 0.72)
  const auto roots = Polynomial{1.0, -1.2, 0.72}.z_roots();
  ASSERT_EQ(roots.size(), 2u);
  EXPECT_TRUE(has_root(roots, {0.6, 0.6}));
  EXPECT_TRUE(has_root(roots, {0.6, -0.6}));
}

TEST(Polynomial, TrailingZeroCoefficientsGiveRootsAtZero) {
  // z^3 (1 - 0.5q + 0q^2 + 0q^3) = z^3 - 0.5 z^2 = z^2 (z - 0.5)
  const auto roots = Polynomial{1.0, -0.5, 0.0, 0.0}.z_roots();
  ASSERT_EQ(roots.size(), 3u);
  EXPECT_TRUE(has_root(roots, 0.5));
  const auto at_zero = std::count_if(roots.begin(), roots.end(), [](auto r) { return std::abs(r) <= kRootTol; });
  EXPECT_EQ(at_zero, 2);
}

TEST(Polynomial, ConstantHasNoRoots) {
  EXPECT_TRUE(Polynomial{3.0}.z_roots().empty());
  EXPECT_TRUE(Polynomial{}.z_roots().empty());
}

TEST(Polynomial, MaxRootAbsPicksTheLargestMagnitude) {
  EXPECT_NEAR((Polynomial{1.0, -0.5} * Polynomial{1.0, 0.3}).max_root_abs(), 0.5, kRootTol);
  EXPECT_NEAR((Polynomial{1.0, 0.3} * Polynomial{1.0, 0.9}).max_root_abs(), 0.9, kRootTol);  // root at -0.9
  EXPECT_NEAR(Polynomial({1.0, -1.2, 0.72}).max_root_abs(), 0.6 * std::sqrt(2.0), kRootTol);
}

TEST(Polynomial, MaxRootAbsOfConstantIsZero) {
  EXPECT_EQ(Polynomial{3.0}.max_root_abs(), 0.0);
}

TEST(Polynomial, RootsDescendingDropsLeadingZeros) {
  // 0 x^3 + 0 x^2 + 2x - 1: one root, at 0.5
  const auto roots = roots_descending({0.0, 0.0, 2.0, -1.0});
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_TRUE(has_root(roots, 0.5));
}

TEST(Polynomial, RootsDescendingOfCubicWithKnownRoots) {
  // (x - 2)(x + 1)(x - 0.5) = x^3 - 1.5x^2 - 1.5x + 1
  const auto roots = roots_descending({1.0, -1.5, -1.5, 1.0});
  ASSERT_EQ(roots.size(), 3u);
  EXPECT_TRUE(has_root(roots, 2.0));
  EXPECT_TRUE(has_root(roots, -1.0));
  EXPECT_TRUE(has_root(roots, 0.5));
}

TEST(Polynomial, ToStringWritesPowersOfQWithSigns) {
  EXPECT_EQ(Polynomial({1.0, -0.5, 0.25}).to_string(), "1 - 0.5q + 0.25q^2");
  EXPECT_EQ(Polynomial({-1.0, 2.0}).to_string(), "-1 + 2q");
}

TEST(Polynomial, ToStringSkipsZeroCoefficients) {
  EXPECT_EQ(Polynomial({1.0, 0.0, -2.0}).to_string(), "1 - 2q^2");
  EXPECT_EQ(Polynomial({0.0, 1.024}).to_string(), "1.024q");
}

TEST(Polynomial, ToStringOfZeroPolynomialIsZero) {
  EXPECT_EQ(Polynomial{}.to_string(), "0");
  EXPECT_EQ(Polynomial{0.0}.to_string(), "0");
  EXPECT_EQ(Polynomial({0.0, 0.0}).to_string(), "0");
}

TEST(Polynomial, ToStringUsesTheGivenVariable) {
  EXPECT_EQ(Polynomial({1.0, -0.5, 0.25}).to_string('z'), "1 - 0.5z + 0.25z^2");
}

TEST(Polynomial, ToStringOfPaperAShowsItsPrintedDigits) {
  // %g-style output drops the trailing zero of 0.6110.
  EXPECT_EQ(kPaperA.to_string(), "1 - 0.9094q - 0.611q^2 + 0.5204q^3");
}

TEST(Polynomial, ToStringWithLowerPrecisionIsShorter) {
  const Polynomial p{0.123456789};
  EXPECT_LT(p.to_string('q', 2).size(), p.to_string('q', 6).size());
  EXPECT_EQ(p.to_string('q', 2).rfind("0.12", 0), 0u) << p.to_string('q', 2);
}

// --- The paper's polynomials, checked (docs/paper.md reads them) ---

TEST(PaperPolynomials, AHasARootAtZEqualOne) {
  // 1 - 0.9094 - 0.6110 + 0.5204 = 1.5204 - 1.5204 = 0: the plant integrates.
  EXPECT_NEAR(kPaperA.at(1.0), 0.0, kArithTol);
  EXPECT_TRUE(has_root(kPaperA.z_roots(), 1.0));
  EXPECT_NEAR(kPaperA.max_root_abs(), 1.0, kRootTol);  // the other roots are 0.6775 and -0.7681
}

TEST(PaperPolynomials, AFactorsAsIntegratorTimesQuadratic) {
  // (1 - q)(1 + 0.0906q - 0.5204q^2) = 1 + (0.0906 - 1) q + (-0.5204 - 0.0906) q^2 + 0.5204 q^3
  const Polynomial product = Polynomial{1.0, -1.0} * Polynomial{1.0, 0.0906, -0.5204};
  expect_coefficients(product, kPaperA.coefficients());
  // The quadratic's roots z^2 + 0.0906 z - 0.5204 = 0: z = (-0.0906 +- sqrt(0.0906^2 + 4*0.5204)) / 2.
  const double disc = std::sqrt(0.0906 * 0.0906 + 4.0 * 0.5204);
  const auto roots = kPaperA.z_roots();
  EXPECT_TRUE(has_root(roots, (-0.0906 + disc) / 2.0));
  EXPECT_TRUE(has_root(roots, (-0.0906 - disc) / 2.0));
}

TEST(PaperPolynomials, BHasTinyStaticGainAndLargeNyquistGain) {
  // B(1) = 1.024 - 2.046 + 1.029 = 0.007; B(-1) = -1.024 - 2.046 - 1.029 = -4.099
  EXPECT_NEAR(kPaperB.at(1.0), 0.007, kArithTol);
  EXPECT_NEAR(kPaperB.at(-1.0), -4.099, kArithTol);
  EXPECT_NEAR(std::abs(kPaperB.at(-1.0)), 4.099, kArithTol);
}

TEST(PaperPolynomials, BZerosAreAComplexPairJustOutsideTheUnitCircle) {
  // z^3 B(1/z) = 1.024 z^2 - 2.046 z + 1.029 (the z^3 coefficient B[0] is 0, so two roots).
  // Discriminant 2.046^2 - 4 * 1.024 * 1.029 = -0.028668 < 0: a conjugate pair with
  // |z|^2 = 1.029 / 1.024.
  const auto roots = kPaperB.z_roots();
  ASSERT_EQ(roots.size(), 2u);
  EXPECT_NEAR(roots[0].imag(), -roots[1].imag(), kRootTol);
  EXPECT_GT(std::abs(roots[0].imag()), 0.05);
  EXPECT_NEAR(kPaperB.max_root_abs(), std::sqrt(1.029 / 1.024), kRootTol);
  EXPECT_GT(kPaperB.max_root_abs(), 1.0024);
}

TEST(PaperPolynomials, TIsIntegratorTimesTheDesiredQuadraticExactly) {
  // (1 - q)(1 - 1.865q + 0.8694q^2) = 1 - 2.865q + (0.8694 + 1.865) q^2 - 0.8694 q^3
  const Polynomial product = Polynomial{1.0, -1.0} * Polynomial{1.0, -1.865, 0.8694};
  expect_coefficients(product, kPaperT.coefficients());
  EXPECT_NEAR(kPaperT.at(1.0), 0.0, kArithTol);
}

TEST(PaperPolynomials, TRootsAreOneAnd0945And092) {
  // z^2 - 1.865 z + 0.8694: discriminant 3.478225 - 3.4776 = 0.000625 = 0.025^2,
  // so z = (1.865 +- 0.025) / 2 = 0.945, 0.92.
  const auto roots = kPaperT.z_roots();
  ASSERT_EQ(roots.size(), 3u);
  EXPECT_TRUE(has_root(roots, 1.0));
  EXPECT_TRUE(has_root(roots, 0.945));
  EXPECT_TRUE(has_root(roots, 0.92));
  for (const auto& r : roots) EXPECT_NEAR(r.imag(), 0.0, kRootTol);
}

}  // namespace
}  // namespace epa::core
