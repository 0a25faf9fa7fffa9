#pragma once
// The Hammerstein model refined on the simulation error: the one-step fit (hammerstein_fit.hpp:
// swarm over the dead zone, least squares inside) gives the start, output_error_fit.hpp moves A, B
// and the dead zone together, and the result is put on the paper's normalisation with the evidence
// for each side of the dead zone. The order search refines every candidate the same way, so orders
// are compared as the models they become, not as least-squares one-step predictors (which, on a
// plant that is not a Hammerstein model, say little about how each simulates).
#include <vector>

#include "core/dead_zone.hpp"
#include "core/result.hpp"
#include "ident/hammerstein_fit.hpp"
#include "ident/ident_data.hpp"
#include "ident/order_selection.hpp"
#include "ident/output_error_fit.hpp"

namespace epa::ident {

struct RefinementOptions {
  OutputErrorOptions output_error;  // criterion, break-point bands (e.g. from ramp_reading.hpp), pole limit
  double m_l = kPaperLeftSlope;     // the normalisation of the result, as HammersteinFitOptions::m_l
};

// Refines (start_model, start_dead_zone) on `segments` (raw valve command u). The break points are
// kept inside the options' bands and the commands' range. The evidence for a side is V_sim with
// that side closed (its break point beyond every command): a side is not identified when that less
// than doubles V_sim, or when its break point sits at the largest command on that side. Errors:
// a command that does not go both ways, and those of fit_output_error.
core::Result<HammersteinFit> refine_hammerstein(const std::vector<Segment>& segments, const ArxModel& start_model,
                                                const core::DeadZone& start_dead_zone, const RefinementOptions& options);

struct RefinedOrderSelection {
  OrderSelection selection;          // each candidate's estimate is its refined ARX part (loss: V_sim)
  std::vector<HammersteinFit> fits;  // the refined model of each candidate, same order
};

// Every order of the search: least squares on u through start_dead_zone (clamped into the bands)
// as the start, refined, then scored and chosen by the rule of order_selection.hpp on the free-run
// fits of the refined models (FPE and AIC count the three dead-zone parameters too).
core::Result<RefinedOrderSelection> select_refined_order(const std::vector<Segment>& estimation,
                                                         const std::vector<Segment>& validation,
                                                         const OrderSearch& search, const core::DeadZone& start_dead_zone,
                                                         const RefinementOptions& options);

}  // namespace epa::ident
