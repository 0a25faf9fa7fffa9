#include "ident/hammerstein_fit.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <pagmo/algorithms/compass_search.hpp>
#include <pagmo/algorithms/pso.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <string>

#include "core/format.hpp"

namespace epa::ident {

namespace {

constexpr double kFailedLoss = 1e300;     // a candidate whose least squares fails
constexpr double kAtBoundFraction = 0.01; // within 1 % of a search range's width counts as "on its bound"
constexpr double kSideEvidence = 2.0;     // a side whose closing less than doubles V is not identified

core::DeadZone unit_dead_zone(const pagmo::vector_double& x) {
  return {.m_r = std::exp(x[0]), .m_l = 1.0, .b_r = x[1], .b_l = x[2]};
}

// The objective: V of the ARX least squares for the u_d a candidate dead zone gives.
class DeadZoneLoss {
 public:
  explicit DeadZoneLoss(ArxRegression regression) : regression_(std::move(regression)) {}

  double operator()(const pagmo::vector_double& x) {
    ++evaluations_;
    regression_.set_input_through(unit_dead_zone(x));
    const auto e = regression_.solve(/*allow_rank_deficient=*/true);
    return e && std::isfinite(e->loss) ? e->loss : kFailedLoss;
  }

  core::Result<ArxEstimate> estimate(const pagmo::vector_double& x) {
    regression_.set_input_through(unit_dead_zone(x));
    return regression_.solve();
  }

  std::size_t evaluations() const { return evaluations_; }

 private:
  ArxRegression regression_;
  std::size_t evaluations_ = 0;
};

// pagmo's user-defined problem: a non-owning handle on the objective (pagmo copies problems).
struct DeadZoneProblem {
  DeadZoneLoss* loss = nullptr;
  pagmo::vector_double lb, ub;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const { return {(*loss)(x)}; }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const { return {lb, ub}; }
};

core::Status validate(const HammersteinFitOptions& o) {
  if (auto s = o.orders.validate(); !s) return s.error();
  if (o.generations > 0 && o.particles < 2)
    return core::invalid_argument("PSO: --particles must be >= 2, got " + std::to_string(o.particles));
  if (!(o.ratio_min > 0.0 && o.ratio_min < o.ratio_max && std::isfinite(o.ratio_max)))
    return core::invalid_argument("dead-zone fit: the m_r/m_l range must satisfy 0 < min < max");
  if (!(o.m_l > 0.0 && std::isfinite(o.m_l)))
    return core::invalid_argument("dead-zone fit: the normalisation m_l must be > 0, got " + core::format_number(o.m_l));
  if (o.generations == 0 && !o.start)
    return core::invalid_argument("dead-zone fit: 0 generations needs a start point to polish");
  return core::ok();
}

}  // namespace

core::HammersteinModel HammersteinFit::model(double Ts, double mm_per_volt) const {
  core::HammersteinModel m;
  m.A = arx.model.A();
  m.B = arx.model.B();
  m.dead_zone = dead_zone;
  m.Ts = Ts;
  m.mm_per_volt = mm_per_volt;
  return m;
}

core::Result<HammersteinFit> fit_hammerstein(const std::vector<Segment>& segments, const HammersteinFitOptions& o) {
  if (auto s = validate(o); !s) return s.error();
  double u_min = 0.0, u_max = 0.0;
  for (const auto& s : segments)
    for (double u : s.u) u_min = std::min(u_min, u), u_max = std::max(u_max, u);
  if (!(u_max > 0.0 && u_min < 0.0))
    return core::invalid_argument("dead-zone fit: the valve command must go both ways (it spans [" +
                                  core::format_number(u_min) + ", " + core::format_number(u_max) + "] V)");
  auto regression = ArxRegression::make(segments, o.orders);
  if (!regression) return regression.error();
  DeadZoneLoss loss(std::move(*regression));

  DeadZoneProblem udp;
  udp.loss = &loss;
  udp.lb = {std::log(o.ratio_min), 0.0, u_min};
  udp.ub = {std::log(o.ratio_max), u_max, 0.0};
  auto clamp_start = [&](const core::DeadZone& dz) {
    pagmo::vector_double x = {std::log(dz.m_r / dz.m_l), dz.b_r, dz.b_l};
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::clamp(x[i], udp.lb[i], udp.ub[i]);
    return x;
  };

  HammersteinFit fit;
  pagmo::vector_double best_x;
  try {
    pagmo::problem prob{udp};
    const auto seed = static_cast<unsigned>(o.seed);
    const auto size = o.generations > 0 ? o.particles : 1u;
    pagmo::population pop{prob, o.generations > 0 ? size - (o.start ? 1u : 0u) : 0u, seed};
    if (o.start) pop.push_back(clamp_start(*o.start));
    if (o.generations > 0) {
      // One generation per evolve() with memory = true is the same swarm as one long evolve(),
      // and lets us report progress in between. Variant 5 (constriction factor), ring topology.
      pagmo::pso pso{1u, 0.7298, 2.05, 2.05, 0.5, 5u, 2u, 4u, /*memory=*/true, seed + 1u};
      for (unsigned g = 1; g <= o.generations; ++g) {
        pop = pso.evolve(pop);
        if (o.progress && (g % std::max(1u, o.progress_every) == 0 || g == o.generations))
          o.progress({g, o.generations, loss.evaluations(), pop.champion_f()[0], unit_dead_zone(pop.champion_x())});
      }
    }
    fit.best_loss_after_swarm = pop.champion_f()[0];
    if (o.polish_evaluations > 0) {
      pagmo::compass_search cs{o.polish_evaluations, 0.02, 1e-10, 0.5};
      pop = cs.evolve(pop);
    }
    best_x = pop.champion_x();
  } catch (const std::exception& e) {
    return core::numerical_error(std::string("dead-zone fit (pagmo): ") + e.what());
  }

  auto arx = loss.estimate(best_x);
  if (!arx) return arx.error();
  fit.evaluations = loss.evaluations();
  fit.ratio = std::exp(best_x[0]);
  // Rescale to m_l := o.m_l: u_d scales by m_l, so B scales by 1 / m_l (the products stay).
  fit.dead_zone = {.m_r = fit.ratio * o.m_l, .m_l = o.m_l, .b_r = best_x[1], .b_l = best_x[2]};
  fit.arx = std::move(*arx);
  for (double& b : fit.arx.model.b) b /= o.m_l;
  // Evidence for each side: how much worse the fit gets with that side closed (its break point
  // beyond every command). A side the data never drive beyond its break point hardly matters.
  auto near = [&](std::size_t i, double bound) { return std::abs(best_x[i] - bound) <= kAtBoundFraction * (udp.ub[i] - udp.lb[i]); };
  pagmo::vector_double closed = best_x;
  closed[1] = u_max + 1.0;
  fit.loss_without_right = loss(closed);
  closed = best_x;
  closed[2] = u_min - 1.0;
  fit.loss_without_left = loss(closed);
  const double best_loss = loss(best_x);
  fit.right_unidentified = near(1, udp.ub[1]) || fit.loss_without_right < kSideEvidence * best_loss;
  fit.left_unidentified = near(2, udp.lb[2]) || fit.loss_without_left < kSideEvidence * best_loss;
  return fit;
}

}  // namespace epa::ident
