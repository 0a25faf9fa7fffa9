#pragma once
// Pole-placement design (`epa design`): the desired characteristic polynomial T from a
// time-domain spec, F and G from the Diophantine equation, and the closed loop of each branch of
// the dead-zone compensation (nominal, u_l active, u_r active) with roots and the Jury verdict.
#include <complex>
#include <string>
#include <vector>

#include "control/jury.hpp"
#include "core/hammerstein_model.hpp"
#include "core/polynomial.hpp"
#include "core/result.hpp"

namespace epa::control {

struct DesignSpec {
  double overshoot_pct = 2.0;  // allowed overshoot of the dominant pair, %
  double settling_s = 2.0;     // 2 % settling time of the dominant pair, s
  double Ts = 0.005;           // sample time, s
  double observer_pole = 0.0;  // z-location of the remaining (non-dominant) poles, in [0, 1)
};

// T = (1 - 2 r cos(theta) q + r^2 q^2) (1 - p q)^(degree - 2): the discretised second-order pair
// with the damping that gives the overshoot and the decay that gives 2 % settling (4 / (zeta wn)),
// the other poles at p. Errors name the field that is out of range.
core::Result<core::Polynomial> characteristic_from_spec(const DesignSpec& spec, int degree);

// An RST design for `model`: T given or from `spec` (degree deg A + deg B - 1), F and G from A F + B G = T,
// all three scaled so F is monic (the law needs it; scaling F, G, T together changes nothing), and
// H = G (error feedback). Used by `epa design` and the commissioning sequence.
struct RstDesign {
  core::Polynomial F, G, H, T;
  double condition_number = 0.0;  // of the Sylvester matrix: how many digits of F, G are determined
};
core::Result<RstDesign> design_for_T(const core::HammersteinModel& model, const core::Polynomial& T);
core::Result<RstDesign> design_from_spec(const core::HammersteinModel& model, const DesignSpec& spec);

struct ClosedLoopBranch {
  std::string name;   // "nominal", "left", "right"
  double gain = 1.0;  // the factor on B G: 1, 1 + m_l, 1 + m_r
  core::Polynomial P; // A F + gain B G, in q^-1 (equal to descending powers of z)
  std::vector<std::complex<double>> roots;
  double max_root_abs = 0.0;
  JuryResult jury;
};

// Nominal A F + B G; left A F + (1 + m_l) B G; right A F + (1 + m_r) B G (docs/paper.md: the FF-IDZ
// term (1 + 1/m*) u + b* through the dead zone gives (1 + m*) u).
std::vector<ClosedLoopBranch> analyse_branches(const core::HammersteinModel& model, const core::Polynomial& F,
                                               const core::Polynomial& G);

}  // namespace epa::control
