#include "plant/force_path.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/polynomial.hpp"
#include "plant/effects.hpp"

namespace epa::plant {

namespace {

// The largest real root of A' in (0, 1), or 0.
double slowest_real_pole(const std::vector<double>& a_prime) {
  double pole = 0.0;
  for (const auto& z : core::Polynomial(a_prime).z_roots())
    if (std::abs(z.imag()) <= 1e-9 && z.real() > 0.0 && z.real() < 1.0) pole = std::max(pole, z.real());
  return pole;
}

}  // namespace

ForcePath force_path(const core::HammersteinModel& model) {
  ForcePath path;
  const auto A = model.A.coefficients();
  const auto B = model.B.coefficients();
  path.speed_mm_s_per_V = steady_speed_mm_s_per_V(A, B, model.Ts, model.mm_per_volt);
  if (A.size() < 2) return path;
  // A' = A / (1 - q^-1): running sums of A's coefficients (A(1) = 0 for an integrating model; a
  // model that integrates only nearly leaves a remainder, ignored as steady_speed_mm_s_per_V does).
  std::vector<double> a_prime(A.size() - 1);
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < A.size(); ++i) a_prime[i] = sum += A[i];
  double b1 = 0.0, a_prime_1 = 0.0;
  for (double b : B) b1 += b;
  for (double a : a_prime) a_prime_1 += a;
  if (a_prime_1 == 0.0) return path;
  path.pole = slowest_real_pole(a_prime);
  // A' / (1 - p q^-1) by synthetic division; its remainder is 0 when p is a root.
  const double k = b1 / a_prime_1, p = path.pole;
  double q = 0.0;
  for (std::size_t i = 0; i < a_prime.size() && i + 1 < path.c.size(); ++i) {
    q = a_prime[i] + p * q;
    if (i + 1 == a_prime.size() && p != 0.0) break;  // the remainder
    path.c[i + 1] = k * (1.0 - p) * q;
    path.nc = i + 1;
  }
  return path;
}

}  // namespace epa::plant
