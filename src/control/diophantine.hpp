#pragma once
// The Diophantine equation of pole placement (paper eq 4): A F + B G = T, solved through the
// Sylvester matrix. The condition number is reported because it decides how many digits of F, G
// the printed digits of A, B, T can determine (docs/paper.md: about 3.6e3 for the paper's model).
#include "core/polynomial.hpp"
#include "core/result.hpp"

namespace epa::control {

struct DiophantineSolution {
  core::Polynomial F;            // degree deg(B) - 1
  core::Polynomial G;            // degree deg(A) - 1
  double condition_number = 0;   // 2-norm condition number of the Sylvester matrix
  double residual_max = 0;       // max |A F + B G - T| coefficient of the computed solution
};

// Minimal-degree solution; T may have degree up to deg(A) + deg(B) - 1. Fails, saying why, when
// A and B share a root (the Sylvester matrix is singular) or T's degree is too high.
core::Result<DiophantineSolution> solve_diophantine(const core::Polynomial& A, const core::Polynomial& B,
                                                    const core::Polynomial& T);

// max |A F + B G - T| over all coefficients: how well a given (e.g. printed) F, G solves eq 4.
double diophantine_residual(const core::Polynomial& A, const core::Polynomial& B, const core::Polynomial& T,
                            const core::Polynomial& F, const core::Polynomial& G);

}  // namespace epa::control
