#include "control/diophantine.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>

namespace epa::control {

using core::Polynomial;

double diophantine_residual(const Polynomial& A, const Polynomial& B, const Polynomial& T, const Polynomial& F,
                            const Polynomial& G) {
  const Polynomial r = A * F + B * G - T;
  double m = 0.0;
  for (double v : r.coefficients()) m = std::max(m, std::abs(v));
  return m;
}

core::Result<DiophantineSolution> solve_diophantine(const Polynomial& A, const Polynomial& B, const Polynomial& T) {
  const int na = A.degree(), nb = B.degree();
  if (na < 1) return core::invalid_argument("Diophantine: A must have degree >= 1");
  if (nb < 1) return core::invalid_argument("Diophantine: B must have degree >= 1");
  const int n = na + nb;  // unknowns: nb coefficients of F, na of G; equations: q^0 .. q^(n-1)
  if (T.degree() > n - 1)
    return core::invalid_argument("Diophantine: T has degree " + std::to_string(T.degree()) +
                                  ", at most deg(A) + deg(B) - 1 = " + std::to_string(n - 1) + " is solvable");

  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int j = 0; j < nb; ++j)
    for (int i = 0; i <= na; ++i) M(i + j, j) = A[static_cast<std::size_t>(i)];
  for (int j = 0; j < na; ++j)
    for (int i = 0; i <= nb; ++i) M(i + j, nb + j) = B[static_cast<std::size_t>(i)];
  Eigen::VectorXd t(n);
  for (int i = 0; i < n; ++i) t(i) = T[static_cast<std::size_t>(i)];

  // With B[0] = 0 (a delay in the plant) the q^0 row only says f0 = t0 / a0; solving the other
  // rows on their own gives the conditioning of what is actually determined (docs/paper.md: 3.6e3).
  const int skip = B[0] == 0.0 ? 1 : 0;
  Eigen::VectorXd x(n);
  if (skip) {
    x(0) = t(0) / A[0];
    t -= M.col(0) * x(0);
  }
  const Eigen::MatrixXd Mr = M.bottomRightCorner(n - skip, n - skip);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Mr);
  const auto& s = svd.singularValues();
  const double smin = s(s.size() - 1);
  if (!(smin > s(0) * 1e-13))
    return core::numerical_error("Diophantine: the Sylvester matrix is singular: A and B share a root, "
                                 "so the closed-loop poles cannot be placed freely");
  x.tail(n - skip) = Mr.colPivHouseholderQr().solve(t.tail(n - skip));

  DiophantineSolution sol;
  std::vector<double> f(static_cast<std::size_t>(nb)), g(static_cast<std::size_t>(na));
  for (int j = 0; j < nb; ++j) f[static_cast<std::size_t>(j)] = x(j);
  for (int j = 0; j < na; ++j) g[static_cast<std::size_t>(j)] = x(nb + j);
  sol.F = Polynomial(std::move(f));
  sol.G = Polynomial(std::move(g));
  sol.condition_number = s(0) / smin;
  sol.residual_max = diophantine_residual(A, B, T, sol.F, sol.G);
  return sol;
}

}  // namespace epa::control
