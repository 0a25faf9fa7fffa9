#include "core/hammerstein_model.hpp"

#include <cmath>
#include <string>

namespace epa::core {

namespace {
Status check_finite(const Polynomial& p, const char* name) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i]))
      return invalid_argument(std::string("model: ") + name + "[" + std::to_string(i) + "] is not a finite number");
  }
  return ok();
}
}  // namespace

Status HammersteinModel::validate() const {
  if (A.size() < 2) return invalid_argument("model: A needs at least 2 coefficients (1, a1, ...)");
  if (B.size() < 1 || B.degree() < 0) return invalid_argument("model: B must have a non-zero coefficient");
  if (auto s = check_finite(A, "A"); !s) return s;
  if (auto s = check_finite(B, "B"); !s) return s;
  if (std::abs(A[0] - 1.0) > 1e-12) return invalid_argument("model: A must be monic (A[0] = 1), got A[0] = " + std::to_string(A[0]));
  if (A.size() - 1 > kMaxModelOrder || B.size() - 1 > kMaxModelOrder)
    return invalid_argument("model: order above the supported maximum of " + std::to_string(kMaxModelOrder));
  if (!(Ts > 0.0) || !std::isfinite(Ts)) return invalid_argument("model: Ts must be a positive number of seconds");
  if (!(mm_per_volt > 0.0) || !std::isfinite(mm_per_volt)) return invalid_argument("model: mm_per_volt must be > 0");
  return dead_zone.validate();
}

double piston_speed_mm_s_per_v(const HammersteinModel& m, double slope) {
  double dA = 0.0;  // A'(1) = sum i a_i
  for (std::size_t i = 1; i < m.A.size(); ++i) dA += static_cast<double>(i) * m.A[i];
  return slope * m.B.at(1.0) / -dA * m.mm_per_volt / m.Ts;
}

}  // namespace epa::core
