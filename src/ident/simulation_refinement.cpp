#include "ident/simulation_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/format.hpp"
#include "ident/arx_metrics.hpp"

namespace epa::ident {

namespace {

constexpr double kSideEvidence = 2.0;      // closing a side must at least double V_sim
constexpr double kAtBoundFraction = 0.01;  // within 1 % of the command range counts as "at the largest command"
constexpr double kStabilisingWindowS = 1.0;  // windows for a start whose whole-run simulation diverges
constexpr std::size_t kDeadZoneParameters = 3;

struct CommandRange {
  double min_v = 0.0, max_v = 0.0;
};

CommandRange command_range(const std::vector<Segment>& segments) {
  CommandRange r;
  for (const auto& s : segments)
    for (double u : s.u) r.min_v = std::min(r.min_v, u), r.max_v = std::max(r.max_v, u);
  return r;
}

// The bands, narrowed to the commands the data hold (a break point beyond them is unknowable).
OutputErrorOptions within_commands(OutputErrorOptions o, const CommandRange& r) {
  o.right.hi_v = std::min(o.right.hi_v, r.max_v);
  o.right.lo_v = std::clamp(o.right.lo_v, 0.0, o.right.hi_v);
  o.left.lo_v = std::max(o.left.lo_v, r.min_v);
  o.left.hi_v = std::clamp(o.left.hi_v, o.left.lo_v, 0.0);
  return o;
}

core::DeadZone clamped(core::DeadZone dz, const OutputErrorOptions& o) {
  dz.b_r = std::clamp(dz.b_r, o.right.lo_v, o.right.hi_v);
  dz.b_l = std::clamp(dz.b_l, o.left.lo_v, o.left.hi_v);
  return dz;
}

}  // namespace

core::Result<HammersteinFit> refine_hammerstein(const std::vector<Segment>& segments, const ArxModel& start,
                                                const core::DeadZone& start_dz, const RefinementOptions& options) {
  if (!(options.m_l > 0.0 && std::isfinite(options.m_l)))
    return core::invalid_argument("refinement: the normalisation m_l must be > 0, got " + core::format_number(options.m_l));
  const CommandRange range = command_range(segments);
  if (!(range.max_v > 0.0 && range.min_v < 0.0))
    return core::invalid_argument("refinement: the valve command must go both ways (it spans [" +
                                  core::format_number(range.min_v) + ", " + core::format_number(range.max_v) + "] V)");
  const OutputErrorOptions o = within_commands(options.output_error, range);
  auto oe = fit_output_error(segments, start, clamped(start_dz, o), o);
  std::size_t evaluations = 0;
  if (!oe && oe.error().code == core::ErrorCode::kNumerical && o.window_s == 0.0) {
    // A start that diverges over a whole run (least squares can leave a pole just outside the
    // unit circle) is first settled on short windows, where it cannot run away.
    OutputErrorOptions windowed = o;
    windowed.window_s = kStabilisingWindowS;
    auto settled = fit_output_error(segments, start, clamped(start_dz, o), windowed);
    if (!settled) return settled.error();
    evaluations += settled->evaluations;
    oe = fit_output_error(segments, settled->model, settled->dead_zone, o);
  }
  if (!oe) return oe.error();

  HammersteinFit fit;
  fit.criterion = FitCriterion::kSimulation;
  fit.ratio = oe->dead_zone.m_r / oe->dead_zone.m_l;
  // Rescale to m_l := options.m_l: u_d scales by m_l, so B scales by 1 / m_l (the products stay).
  fit.dead_zone = {.m_r = fit.ratio * options.m_l, .m_l = options.m_l, .b_r = oe->dead_zone.b_r, .b_l = oe->dead_zone.b_l};
  fit.arx.model = oe->model;
  for (double& b : fit.arx.model.b) b /= options.m_l;
  fit.arx.N = oe->samples;
  fit.arx.loss = oe->loss;
  fit.arx.rank = static_cast<std::size_t>(oe->model.orders.d()) + kDeadZoneParameters;
  fit.evaluations = evaluations + oe->evaluations;
  fit.best_loss_after_swarm = oe->start_loss;

  // Evidence for each side, on the criterion itself.
  const auto window = static_cast<std::size_t>(std::llround(o.window_s / o.Ts));
  core::DeadZone closed = oe->dead_zone;
  closed.b_r = range.max_v + 1.0;
  fit.loss_without_right = windowed_simulation_loss(segments, oe->model, closed, window);
  closed = oe->dead_zone;
  closed.b_l = range.min_v - 1.0;
  fit.loss_without_left = windowed_simulation_loss(segments, oe->model, closed, window);
  const bool right_at_edge = oe->dead_zone.b_r >= range.max_v - kAtBoundFraction * range.max_v;
  const bool left_at_edge = oe->dead_zone.b_l <= range.min_v - kAtBoundFraction * range.min_v;
  fit.right_unidentified = right_at_edge || !(fit.loss_without_right >= kSideEvidence * oe->loss);
  fit.left_unidentified = left_at_edge || !(fit.loss_without_left >= kSideEvidence * oe->loss);
  return fit;
}

core::Result<RefinedOrderSelection> select_refined_order(const std::vector<Segment>& est, const std::vector<Segment>& val,
                                                         const OrderSearch& search, const core::DeadZone& start_dz,
                                                         const RefinementOptions& options) {
  RefinedOrderSelection out;
  OrderSelection& sel = out.selection;
  sel.first = common_first_row(search);
  const bool validating = !val.empty();
  const core::DeadZone start = clamped(start_dz, within_commands(options.output_error, command_range(est)));
  const auto est_ud = through_dead_zone(est, start);
  for (int nk = search.nk.lo; nk <= search.nk.hi; ++nk)
    for (int na = search.na.lo; na <= search.na.hi; ++na)
      for (int nb = search.nb.lo; nb <= search.nb.hi; ++nb) {
        const ArxOrders orders{.na = na, .nb = nb, .nk = nk};
        if (auto s = orders.validate(); !s) return core::invalid_argument("order search: " + s.error().message);
        auto ls = estimate_arx(est_ud, orders, sel.first);
        if (!ls) {
          sel.skipped.push_back(orders.to_string() + ": " +
                                (ls.error().code == core::ErrorCode::kNumerical
                                     ? "rank-deficient regression (more parameters than these data determine)"
                                     : ls.error().message));
          continue;
        }
        auto fit = refine_hammerstein(est, ls->model, start, options);
        if (!fit) {
          sel.skipped.push_back(orders.to_string() + ": " + fit.error().message);
          continue;
        }
        OrderCandidate c;
        c.estimate = fit->arx;
        c.estimation = fit_percent(fit->arx.model, through_dead_zone(est, fit->dead_zone), sel.first);
        if (validating) c.validation = fit_percent(fit->arx.model, through_dead_zone(val, fit->dead_zone), sel.first);
        c.criteria = information_criteria(fit->arx.loss, fit->arx.N, orders.d() + static_cast<int>(kDeadZoneParameters));
        c.score_pct = validating ? c.validation->simulation_pct : c.estimation.simulation_pct;
        c.pole_zero_distance = pole_zero_distance(fit->arx.model);
        c.cancels = c.pole_zero_distance < search.cancellation_distance;
        sel.candidates.push_back(std::move(c));
        out.fits.push_back(std::move(*fit));
      }
  if (auto s = apply_order_rule(sel, search, validating); !s) return s.error();
  return out;
}

}  // namespace epa::ident
