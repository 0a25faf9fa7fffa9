#pragma once
// The Hammerstein fit: the valve dead zone (eq 2) and the ARX part (eq 1) estimated together.
// Particle Swarm Optimisation (pagmo2) searches the dead-zone parameters; inside every evaluation
// the ARX part is the least-squares solution (arx_estimator.hpp) for the dead-zone output u_d, and
// the swarm minimises that solution's loss V (the one-step residual variance). A deterministic
// compass search (pagmo2) then polishes the swarm's best point. The swarm's initial positions and
// moves come from `seed` alone and everything runs in the calling thread, so a run is repeatable.
//
// Normalisation. The data determine only the products m_r B and m_l B: doubling both slopes and
// halving B gives the same output. The search therefore fixes m_l = 1 and works on
//   x = (ln(m_r / m_l), b_r, b_l),   b_r in [0, largest positive u],  b_l in [most negative u, 0],
// and the result is rescaled to m_l := options.m_l (the paper's 1.0707 by default) with B divided by
// the same factor. With that convention the fit of data from the paper's plant returns eq 9 and
// eq 10 themselves, and the FF-IDZ loop gain (1 + m*) B G of a design (docs/paper.md, eq 14-15), which
// is NOT invariant under the rescaling, has the meaning it has in the paper. Break points and the
// ratio m_r / m_l do not depend on the convention and compare directly with eq 10.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "core/dead_zone.hpp"
#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "ident/arx_estimator.hpp"
#include "ident/ident_data.hpp"

namespace epa::ident {

inline constexpr double kPaperLeftSlope = 1.0707;  // eq 10's m_l, the default normalisation

struct FitProgress {
  unsigned generation = 0;     // generations done
  unsigned generations = 0;    // generations planned
  std::size_t evaluations = 0; // least-squares solves so far
  double best_loss = 0.0;      // the swarm's best V so far
  core::DeadZone best;         // its dead zone, with m_l = 1
};

struct HammersteinFitOptions {
  ArxOrders orders;                  // of the linear part
  std::uint64_t seed = 1;            // the swarm's initial positions and random moves
  unsigned particles = 40;
  unsigned generations = 100;        // 0: no swarm, only the polish from `start`
  double ratio_min = 0.05, ratio_max = 20.0;  // search range of m_r / m_l
  double m_l = kPaperLeftSlope;      // the normalisation the result is scaled to
  unsigned polish_evaluations = 600; // compass-search budget (0: none)
  std::optional<core::DeadZone> start;  // added to the initial swarm (slopes: only m_r / m_l counts)
  std::function<void(const FitProgress&)> progress;  // called every `progress_every` generations
  unsigned progress_every = 10;
};

// What a fit minimised: the one-step prediction error (the swarm with least squares inside) or the
// simulation error (simulation_refinement.hpp).
enum class FitCriterion { kOneStep, kSimulation };

struct HammersteinFit {
  core::DeadZone dead_zone;        // scaled: dead_zone.m_l == options.m_l
  ArxEstimate arx;                 // the linear part on the same scale (B divided by m_l); arx.loss is the criterion's V
  FitCriterion criterion = FitCriterion::kOneStep;
  double ratio = 1.0;              // m_r / m_l
  std::size_t evaluations = 0;     // least-squares solves (one-step) or simulations (simulation error) used
  double best_loss_after_swarm = 0.0;  // simulation criterion: V_sim of the least-squares start
  // V with one side closed (its break point moved beyond every command): the evidence for that side.
  double loss_without_right = 0.0, loss_without_left = 0.0;
  // A side the data never drive beyond its break point, so its break point and slope are unknown:
  // the break point sits on the edge of its search range (the largest command on that side), or
  // closing that side less than doubles V (the fit explains a piston that hardly moved that way by
  // a slope near 0 and a break point anywhere).
  bool right_unidentified = false, left_unidentified = false;

  core::HammersteinModel model(double Ts, double mm_per_volt) const;
};

// Segments hold the raw valve command u. Errors: invalid options, data that cannot carry the
// fit (no command on one side of 0), a least-squares failure at the optimum, a pagmo exception.
core::Result<HammersteinFit> fit_hammerstein(const std::vector<Segment>& segments, const HammersteinFitOptions& options);

}  // namespace epa::ident
