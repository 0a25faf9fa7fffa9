#include "control/diophantine.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/paper_reference.hpp"
#include "../support/text_contains.hpp"

namespace epa::control {
namespace {

using core::Polynomial;

// Small well-conditioned systems of short decimals: the solution is exact to a few ulps.
constexpr double kHandTol = 1e-12;
// max |A F + B G - T| of a computed solution: rounding of a backward-stable solve on
// coefficients of size ~3, far below this bound.
constexpr double kResidualTol = 1e-12;
// The re-solved paper F, G below are given to 5 decimals (rounded; docs/paper.md prints 4): half a
// unit in the 5th decimal is 5e-6, and 5e-5 leaves room for the last digit either way.
constexpr double kNotesDigitsTol = 5e-5;

// The paper's model and desired polynomial (eq 9 and 11).
const Polynomial kA{1.0, -0.9094, -0.6110, 0.5204};
const Polynomial kB{0.0, 1.024, -2.046, 1.029};
const Polynomial kT{1.0, -2.865, 2.7344, -0.8694};

using epa::test::contains;

void expect_coefficients(const Polynomial& p, const std::vector<double>& expected, double tol) {
  ASSERT_EQ(p.size(), expected.size()) << p.to_string();
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(p[i], expected[i], tol) << "coefficient " << i;
}

TEST(Diophantine, FirstOrderPlantWithDelaySolvedByHand) {
  // A = 1 - 0.5q, B = q, T = 1 - 0.2q; F = f0, G = g0:
  // f0 (1 - 0.5q) + g0 q = f0 + (g0 - 0.5 f0) q  =>  f0 = 1, g0 - 0.5 = -0.2, g0 = 0.3.
  const auto sol = solve_diophantine({1.0, -0.5}, {0.0, 1.0}, {1.0, -0.2});
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  expect_coefficients(sol->F, {1.0}, kHandTol);
  expect_coefficients(sol->G, {0.3}, kHandTol);
  EXPECT_LT(sol->residual_max, kResidualTol);
  EXPECT_GT(sol->condition_number, 0.0);
}

TEST(Diophantine, FirstOrderPlantWithoutDelaySolvedByHand) {
  // A = 1 - 0.5q, B = 1 + 0.5q, T = 1 - 0.2q:
  // (f0 + g0) + 0.5 (g0 - f0) q  =>  f0 + g0 = 1, g0 - f0 = -0.4  =>  f0 = 0.7, g0 = 0.3.
  const auto sol = solve_diophantine({1.0, -0.5}, {1.0, 0.5}, {1.0, -0.2});
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  expect_coefficients(sol->F, {0.7}, kHandTol);
  expect_coefficients(sol->G, {0.3}, kHandTol);
  EXPECT_LT(sol->residual_max, kResidualTol);
}

TEST(Diophantine, SecondOrderPlantSolvedByHand) {
  // A = 1 - 1.5q + 0.7q^2, B = q, T = (1 - 0.3q)^2 = 1 - 0.6q + 0.09q^2; F = f0, G = g0 + g1 q:
  // f0 = 1; -1.5 + g0 = -0.6 => g0 = 0.9; 0.7 + g1 = 0.09 => g1 = -0.61.
  const auto sol = solve_diophantine({1.0, -1.5, 0.7}, {0.0, 1.0}, {1.0, -0.6, 0.09});
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  expect_coefficients(sol->F, {1.0}, kHandTol);
  expect_coefficients(sol->G, {0.9, -0.61}, kHandTol);
  EXPECT_LT(sol->residual_max, kResidualTol);
}

TEST(Diophantine, ResidualOfTheSolutionIsAtRoundingLevel) {
  const auto sol = solve_diophantine({1.0, -1.5, 0.7}, {0.0, 1.0, 0.5}, {1.0, -0.6, 0.09});
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  // Checked independently of the solver's own residual_max.
  EXPECT_LT(diophantine_residual({1.0, -1.5, 0.7}, {0.0, 1.0, 0.5}, {1.0, -0.6, 0.09}, sol->F, sol->G), kResidualTol);
  EXPECT_LT(sol->residual_max, kResidualTol);
  EXPECT_EQ(sol->F.size(), 2u);  // deg F = deg B - 1
  EXPECT_EQ(sol->G.size(), 2u);  // deg G = deg A - 1
}

TEST(Diophantine, PaperModelResolvedGivesTheNotesSolution) {
  const auto sol = solve_diophantine(kA, kB, kT);
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  expect_coefficients(sol->F, {1.0, -1.76536, 0.77057}, kNotesDigitsTol);
  expect_coefficients(sol->G, {-0.18578, 0.57549, -0.38970}, kNotesDigitsTol);
  EXPECT_LT(sol->residual_max, kResidualTol);
}

TEST(Diophantine, PaperModelSylvesterSystemIsIllConditioned) {
  const auto sol = solve_diophantine(kA, kB, kT);
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  // docs/paper.md: condition number about 3.6e3.
  EXPECT_GT(sol->condition_number, 3.4e3);
  EXPECT_LT(sol->condition_number, 3.8e3);
}

TEST(Diophantine, PaperExactSolutionHasNoIntegralActionInG) {
  // A(1) = 0 and T(1) = 0, so A(1)F(1) + B(1)G(1) = T(1) reduces to 0.007 G(1) = 0: G(1) = 0,
  // i.e. the exact controller has zero static gain (docs/paper.md: the exact loop has a root at 1).
  const auto sol = solve_diophantine(kA, kB, kT);
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  EXPECT_NEAR(sol->G.at(1.0), 0.0, 1e-9);  // 1e-9: cond 3.6e3 times rounding, with margin
}

TEST(Diophantine, PrintedPaperControllerLeavesASmallResidual) {
  // Eq 12-13 rounded: by exact rational arithmetic the worst coefficient of A F + B G - T is
  // the q^5 one, 0.5204 * 0.7828 + 1.029 * (-0.3958) = 0.40736912 - 0.40727820 = 9.092e-5.
  const double r = diophantine_residual(kA, kB, kT, core::paper::F(), core::paper::G());
  EXPECT_GT(r, 5e-5);
  EXPECT_LT(r, 9.2e-5);
}

TEST(Diophantine, ResidualOfAnExactHandSolutionIsZero) {
  EXPECT_NEAR(diophantine_residual({1.0, -0.5}, {0.0, 1.0}, {1.0, -0.2}, {1.0}, {0.3}), 0.0, kHandTol);
  // A wrong G shows up: g0 = 0.4 leaves 0.1 on the q coefficient.
  EXPECT_NEAR(diophantine_residual({1.0, -0.5}, {0.0, 1.0}, {1.0, -0.2}, {1.0}, {0.4}), 0.1, kHandTol);
}

TEST(Diophantine, CommonRootOfAAndBIsRefused) {
  // A = (1 - 0.5q)(1 - q) = 1 - 1.5q + 0.5q^2, B = q (1 - 0.5q) = q - 0.5q^2: both vanish at
  // z = 0.5, so no F, G can move that pole.
  const auto sol = solve_diophantine({1.0, -1.5, 0.5}, {0.0, 1.0, -0.5}, {1.0, -0.6, 0.09});
  ASSERT_FALSE(sol.has_value());
  EXPECT_TRUE(contains(sol.error().message, "share a root"));
}

TEST(Diophantine, CommonRootWithoutDelayIsRefused) {
  // A = 1 - 0.5q, B = 2 - q = 2 (1 - 0.5q).
  const auto sol = solve_diophantine({1.0, -0.5}, {2.0, -1.0}, {1.0, -0.2});
  ASSERT_FALSE(sol.has_value());
  EXPECT_TRUE(contains(sol.error().message, "share a root"));
}

TEST(Diophantine, TOfTooHighDegreeIsRefused) {
  // deg A + deg B - 1 = 5 for the paper's model: T of degree 6 is not solvable at minimal degree.
  const Polynomial T6 = kT * Polynomial{1.0, -0.5, 0.0, 0.25};
  ASSERT_EQ(T6.degree(), 6);
  const auto sol = solve_diophantine(kA, kB, T6);
  ASSERT_FALSE(sol.has_value());
  EXPECT_TRUE(contains(sol.error().message, "degree"));
}

TEST(Diophantine, TOfMaximalDegreeIsSolved) {
  // Degree 5 = deg A + deg B - 1 is the largest accepted.
  const Polynomial T5 = kT * Polynomial{1.0, -0.5, 0.06};  // extra poles at 0.3 and 0.2
  ASSERT_EQ(T5.degree(), 5);
  const auto sol = solve_diophantine(kA, kB, T5);
  ASSERT_TRUE(sol.has_value()) << sol.error().message;
  EXPECT_LT(diophantine_residual(kA, kB, T5, sol->F, sol->G), kResidualTol);
}

TEST(Diophantine, ConstantAIsRefused) {
  const auto sol = solve_diophantine({1.0}, {0.0, 1.0}, {1.0});
  ASSERT_FALSE(sol.has_value());
  EXPECT_TRUE(contains(sol.error().message, "degree"));
}

}  // namespace
}  // namespace epa::control
