#pragma once
// Output-error refinement of a Hammerstein model: every parameter (A, B and the dead zone) is
// moved to minimise the SIMULATION error of the model on the data, not its one-step prediction
// error.
//
// Why. A one-step predictor of a 5 ms position signal is y(k-1) + Ts * velocity: the measured
// y(k-1), y(k-2) in its regressors already carry almost everything, so its residual barely feels
// the input and hence the dead zone. On a plant that is not a Hammerstein model (friction,
// compressibility, a valve that fills a chamber before the piston moves) the least-squares
// one-step model then simulates badly and its break points sit wherever the swarm stopped. The
// simulation error is what the model is used for (a controller design, a simulated step): it
// integrates the input through the model's own dynamics, so a wrong break point, slope or gain
// shows as a growing position error.
//
// Criterion: each segment (a run, or a piece between end stops) is simulated from its first
// samples on the recorded valve command alone, and
//   V_sim = (1/N) sum over segments and samples (y(k) - yhat(k))^2
// is minimised: the free-run fit that `epa identify` reports, as a loss. Its initial state is the
// measured y before the segment smoothed by a line (sensor noise would otherwise start an
// integrating model with a velocity it carries as an offset ever after). The reported fit starts
// from the past that best follows the first samples instead (arx_metrics.hpp), which keeps that
// noise out as well and is exact on noise-free data. With `window_s` > 0 the simulation restarts
// from the measured y every window_s (multiple shooting): a weaker criterion for the slow
// behaviour, kept for data whose drift no model explains.
//
// Whole segments, not windows, by default: the piston integrates, so what the model gets wrong
// slowly (the balance between the two sides' gains, friction that creeps) shows only over long
// horizons, and that is exactly what a free run of the model (and a controller relying on the
// model's gains) depends on. On the physics plant (pneumatic_plant.hpp) no window length did
// clearly better on validation runs, and short ones much worse (docs/identification.md).
//
// Method: Levenberg-Marquardt with the exact Jacobian of the simulation (the sensitivity of yhat to
// each parameter runs through the same recursion as yhat itself; the dead zone's derivatives exist
// everywhere except at the break points). Break points and the slope ratio are kept within bounds
// (a parameter pressed against its bound leaves the step), poles within a radius. Deterministic.
// With `integrating`, A is written as (1 - q) C(q): the model keeps its pole at z = 1 exactly (the
// piston integrates the valve opening) instead of a pole at 1.00003 that grows over a long run.
//
// Normalisation as the dead-zone search (hammerstein_fit.hpp): m_l = 1, B carries the gain.
#include <cstddef>
#include <limits>
#include <vector>

#include "core/dead_zone.hpp"
#include "core/result.hpp"
#include "ident/arx_estimator.hpp"
#include "ident/ident_data.hpp"

namespace epa::ident {

struct BreakPointRange {
  double lo_v = -std::numeric_limits<double>::infinity();
  double hi_v = std::numeric_limits<double>::infinity();
};

struct OutputErrorOptions {
  double Ts = 0.005;              // s, to turn window_s into samples
  double window_s = 0.0;          // > 0: simulation restarted from the measured y every window_s
  bool integrating = true;        // A keeps a root at z = 1 (needs na >= 1)
  unsigned max_iterations = 100;  // Levenberg-Marquardt iterations (each one Jacobian)
  double ratio_min = 0.05, ratio_max = 20.0;  // m_r / m_l
  // Poles other than the integrator are kept at least this fast: |z| <= exp(-Ts / slowest_mode_s)
  // (0: no limit). The cylinder's own modes apart from its integration (the spool, the chambers
  // filling, the air spring against friction) settle within tens of ms; a pole slower than that
  // mimics friction creep in the fit, and it carries an error in a simulation's initial state (the
  // sensor noise on its first samples) as an offset of up to 1/(1 - |z|) times that error.
  double slowest_mode_s = 0.05;
  BreakPointRange right{0.0, std::numeric_limits<double>::infinity()};
  BreakPointRange left{-std::numeric_limits<double>::infinity(), 0.0};

  core::Status validate() const;  // messages name the field
};

struct OutputErrorFit {
  ArxModel model;             // A, B on the unit normalisation (m_l = 1)
  core::DeadZone dead_zone;   // m_l = 1
  double start_loss = 0.0;    // V_sim of the start point, V^2
  double loss = 0.0;          // V_sim at the end
  std::size_t samples = 0;    // N: simulated samples scored
  unsigned iterations = 0;    // Jacobians evaluated
  std::size_t evaluations = 0;  // simulations run (with or without the Jacobian)
};

// Refines (start_model, start_dead_zone; any m_l) on `segments` (raw valve command u). The start's
// break points are clamped into the bounds. Errors: invalid options or orders, a start model whose
// simulation diverges, segments too short for a window.
core::Result<OutputErrorFit> fit_output_error(const std::vector<Segment>& segments, const ArxModel& start_model,
                                              const core::DeadZone& start_dead_zone, const OutputErrorOptions& options);

// V_sim of a model (dead zone applied to the raw u) with windows of `window_samples` (0: whole
// segments). Infinite when the simulation diverges.
double windowed_simulation_loss(const std::vector<Segment>& segments, const ArxModel& model,
                                const core::DeadZone& dead_zone, std::size_t window_samples);

}  // namespace epa::ident
