#include "ident/hammerstein_identification.hpp"

#include <cstdio>
#include <string>

#include "ident/simulation_refinement.hpp"

namespace epa::ident {

std::string unidentified_side_message(const HammersteinFit& fit) {
  // Each side that is not identified, with its evidence: a run that drives neither far enough
  // needs larger pulses on both.
  std::string sides, evidence;
  for (const bool right : {true, false}) {
    if (!(right ? fit.right_unidentified : fit.left_unidentified)) continue;
    char text[240];
    std::snprintf(text, sizeof text, "b_%s = %g V, m_r/m_l = %g; with that side closed V grows only from %.3g to %.3g",
                  right ? "r" : "l", right ? fit.dead_zone.b_r : fit.dead_zone.b_l, fit.ratio, fit.arx.loss,
                  right ? fit.loss_without_right : fit.loss_without_left);
    sides += std::string(sides.empty() ? "the " : " and the ") + (right ? "right" : "left");
    evidence += std::string(evidence.empty() ? "" : "; ") + text;
  }
  const bool both = fit.right_unidentified && fit.left_unidentified;
  return sides + (both ? " sides" : " side") + " of the dead zone " + (both ? "are" : "is") + " not identified (" +
         evidence + "): the runs never drive the valve far enough beyond the dead band on " +
         (both ? "those sides" : "that side") +
         ", so its break point and slope cannot be identified; record runs with larger pulses (epa excite --amplitude-max)";
}

core::Result<Identification> identify_hammerstein(const std::vector<Segment>& est, const std::vector<Segment>& val,
                                                  const IdentificationOptions& o) {
  auto swarm = fit_hammerstein(est, o.swarm);
  if (!swarm) return swarm.error();
  Identification id;
  id.swarm_evaluations = swarm->evaluations;

  if (o.criterion == FitCriterion::kSimulation) {
    RefinementOptions refine;
    refine.output_error.Ts = o.Ts;
    refine.output_error.window_s = o.window_s;
    if (o.ramp_band) {
      auto band = read_dead_band(est, {.Ts = o.Ts, .mm_per_volt = o.mm_per_volt});
      if (!band) return band.error();
      if (band->right) refine.output_error.right = *band->right;
      if (band->left) refine.output_error.left = *band->left;
      id.dead_band = std::move(*band);
    }
    refine.output_error.ratio_min = o.swarm.ratio_min;
    refine.output_error.ratio_max = o.swarm.ratio_max;
    refine.m_l = o.swarm.m_l;
    auto refined = select_refined_order(est, val, o.search, swarm->dead_zone, refine);
    if (!refined) return refined.error();
    id.fit = std::move(refined->fits[refined->selection.recommended]);
    id.selection = std::move(refined->selection);
    // Judged on the refined model: the one-step loss of the swarm hardly sees a side of a plant
    // that integrates (its residual is a velocity error), so its verdict is not asked here.
    if (id.fit.right_unidentified || id.fit.left_unidentified)
      return core::invalid_argument(unidentified_side_message(id.fit));
  } else {
    if (swarm->right_unidentified || swarm->left_unidentified) return core::invalid_argument(unidentified_side_message(*swarm));
    auto selection = select_order(through_dead_zone(est, swarm->dead_zone), through_dead_zone(val, swarm->dead_zone), o.search);
    if (!selection) return selection.error();
    const ArxOrders chosen = selection->candidates[selection->recommended].estimate.model.orders;
    id.selection = std::move(*selection);
    if (chosen == o.swarm.orders) {
      id.fit = std::move(*swarm);
      id.swarm_evaluations = 0;  // counted in the fit itself
    } else {
      HammersteinFitOptions polish = o.swarm;
      polish.orders = chosen;
      polish.generations = 0;
      polish.start = swarm->dead_zone;
      polish.progress = nullptr;
      auto polished = fit_hammerstein(est, polish);
      if (!polished) return polished.error();
      id.fit = std::move(*polished);
    }
  }
  return id;
}

}  // namespace epa::ident
