#pragma once
// Order selection for the linear part: every (na, nb, nk) in the user's ranges is estimated on the
// estimation segments and scored on them and on the validation segments (arx_metrics.hpp), like the
// toolbox's arxstruc/selstruc, and one order is recommended by a stated rule:
//
//   1. Set aside candidates with a near pole-zero cancellation (a root of A and one of B closer than
//      `cancellation_distance` in z): the pair cancels in B/A, so it only fits noise, and it makes
//      the pole-placement design of the model (the Sylvester matrix of A and B) ill-conditioned.
//      (If every candidate has one, none is set aside.)
//   2. Rank the others by the free-run simulation fit on the validation data (on the estimation
//      data when no validation run is given: then say so, since a bigger model always fits its own
//      data better).
//   3. Keep the candidates within `tolerance_pct` fit points of the best: differences that small
//      are noise, not structure.
//   4. Of those, take the fewest parameters d = na + nb (parsimony: fewer coefficients are better
//      determined and give a simpler controller); among equally small ones, the lowest AIC.
//
// Every candidate scores the same samples (from the largest first_row in the ranges), so their fits
// compare like for like.
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "ident/arx_estimator.hpp"
#include "ident/arx_metrics.hpp"

namespace epa::ident {

struct OrderRange {
  int lo = 1, hi = 1;
};

// "3" or "1:4" (inclusive). `option` names the option in messages ("--na").
core::Result<OrderRange> parse_order_range(const std::string& text, const std::string& option);

struct OrderSearch {
  OrderRange na{1, 4}, nb{1, 4}, nk{1, 2};
  double tolerance_pct = 0.5;
  double cancellation_distance = 0.01;
};

struct OrderCandidate {
  ArxEstimate estimate;
  Fit estimation;                 // fits on the estimation segments
  std::optional<Fit> validation;  // fits on the validation segments, when given
  InformationCriteria criteria;
  double score_pct = 0.0;         // the fit the rule ranks by
  double pole_zero_distance = 0.0; // the smallest |pole - zero| in z (infinite without zeros)
  bool cancels = false;            // pole_zero_distance < cancellation_distance: set aside
};

struct OrderSelection {
  std::vector<OrderCandidate> candidates;  // in search order (nk, na, nb ascending)
  std::size_t recommended = 0;             // index into candidates
  std::size_t best = 0;                    // index of the best score among those not set aside
  std::size_t first = 0;                   // first scored sample of each segment
  std::string reason;                      // the rule applied to these numbers, in words
  std::vector<std::string> skipped;        // candidates that could not be estimated, and why
};

// The smallest distance in z between a root of A and a root of B (B's roots at z = 0 from the delay
// excluded); infinity when either has none.
double pole_zero_distance(const ArxModel& model);

// The largest first_row over the search (every candidate can score from there).
std::size_t common_first_row(const OrderSearch& search);

// Segments hold the input of the linear part (u_d, or u for a purely linear plant).
core::Result<OrderSelection> select_order(const std::vector<Segment>& estimation,
                                          const std::vector<Segment>& validation, const OrderSearch& search);

// The rule above applied to candidates already scored (score_pct, cancels, criteria set): sets best,
// recommended and reason. Errors: no candidates (the first skipped reason is given).
core::Status apply_order_rule(OrderSelection& selection, const OrderSearch& search, bool validating);

// The table as printed by `epa identify`: one line per candidate, the recommendation marked.
std::string format_order_table(const OrderSelection& selection);

}  // namespace epa::ident
