#include "control/pole_placement_design.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "control/diophantine.hpp"

namespace epa::control {

using core::Polynomial;

core::Result<Polynomial> characteristic_from_spec(const DesignSpec& s, int degree) {
  if (!(s.overshoot_pct >= 0.0 && s.overshoot_pct < 100.0))
    return core::invalid_argument("design spec: overshoot must be in [0, 100) %, got " + std::to_string(s.overshoot_pct));
  if (!(s.settling_s > 0.0 && std::isfinite(s.settling_s)))
    return core::invalid_argument("design spec: settling time must be > 0 s, got " + std::to_string(s.settling_s));
  if (!(s.Ts > 0.0 && std::isfinite(s.Ts))) return core::invalid_argument("design spec: Ts must be > 0 s");
  if (!(s.observer_pole >= 0.0 && s.observer_pole < 1.0))
    return core::invalid_argument("design spec: observer pole must be in [0, 1), got " + std::to_string(s.observer_pole));
  if (degree < 2) return core::invalid_argument("design spec: T needs degree >= 2 for the dominant pair");

  // Damping from overshoot (zeta = 1 for 0 %), decay rate from the 2 % settling rule 4 / (zeta wn).
  const double os = s.overshoot_pct / 100.0;
  const double zeta = os > 0.0 ? -std::log(os) / std::sqrt(std::numbers::pi * std::numbers::pi + std::log(os) * std::log(os)) : 1.0;
  const double sigma = 4.0 / s.settling_s;
  const double wd = zeta < 1.0 ? sigma * std::sqrt(1.0 - zeta * zeta) / zeta : 0.0;
  const double r = std::exp(-sigma * s.Ts);
  Polynomial T = {1.0, -2.0 * r * std::cos(wd * s.Ts), r * r};
  for (int i = 2; i < degree; ++i) T = T * Polynomial{1.0, -s.observer_pole};
  return T;
}

core::Result<RstDesign> design_from_spec(const core::HammersteinModel& model, const DesignSpec& spec) {
  auto T = characteristic_from_spec(spec, model.A.degree() + model.B.degree() - 1);
  if (!T) return T.error();
  return design_for_T(model, *T);
}

core::Result<RstDesign> design_for_T(const core::HammersteinModel& model, const Polynomial& T) {
  auto sol = solve_diophantine(model.A, model.B, T);
  if (!sol) return sol.error();
  const double f0 = sol->F[0];
  if (!(std::abs(f0) > 0.0 && std::isfinite(f0))) return core::numerical_error("design: F(0) is 0, F cannot be made monic");
  RstDesign d;
  d.F = sol->F * (1.0 / f0);
  d.G = sol->G * (1.0 / f0);
  d.T = T * (1.0 / f0);
  d.H = d.G;
  d.condition_number = sol->condition_number;
  return d;
}

std::vector<ClosedLoopBranch> analyse_branches(const core::HammersteinModel& model, const Polynomial& F,
                                               const Polynomial& G) {
  const Polynomial AF = model.A * F;
  const Polynomial BG = model.B * G;
  std::vector<ClosedLoopBranch> branches = {
      {"nominal", 1.0, {}, {}, 0.0, {}},
      {"left", 1.0 + model.dead_zone.m_l, {}, {}, 0.0, {}},
      {"right", 1.0 + model.dead_zone.m_r, {}, {}, 0.0, {}},
  };
  for (auto& b : branches) {
    b.P = AF + BG * b.gain;
    b.roots = b.P.z_roots();
    b.max_root_abs = 0.0;
    for (const auto& root : b.roots) b.max_root_abs = std::max(b.max_root_abs, std::abs(root));
    b.jury = jury_test(b.P.coefficients());
  }
  return branches;
}

}  // namespace epa::control
