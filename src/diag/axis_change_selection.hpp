#pragma once
// What changed since commissioning: forward selection of axis changes (axis_change.hpp) against
// the commissioned stick-slip model, on the gap over whole moves. A change is accepted while the
// best one left shrinks the held-out gap by more than kChangeThresholdPct of the commissioned
// model's gap and lies beyond the commissioned model's tolerance; at most kMaxChanges.
// Readings that move while the valve rests (a leak, a load on the rod) make the change
// unexplained: no change of the model's terms moves a piston there.
#include <optional>
#include <span>
#include <vector>

#include "diag/axis_change_fit.hpp"

namespace epa::diag {

inline constexpr double kChangeThresholdPct = 10.0;
inline constexpr std::size_t kMaxChanges = 2;

struct ChangeCandidate {
  ChangeTerm term;
  ChangeFit fit;               // the change alone (round 1)
  double reduction_pct = 0.0;  // of the commissioned model's held-out gap
  bool beyond_tolerance = false;
};

struct AxisChanges {
  double commissioned_heldout_mm = 0.0, commissioned_train_mm = 0.0;
  std::vector<ChangeCandidate> candidates;  // round 1, best first
  AxisChange accepted;                       // the named changes, with their joint fit
  double heldout_after_mm = 0.0;
  double reduction_pct = 0.0;
  bool unexplained = false;
  bool judged = false;  // the model file holds the model's spread: changes can be named
  // A coarser sensor, seen in the readings themselves (sensor_resolution.hpp): the model file's
  // runs were read finer, or the model would say so.
  std::optional<double> sensor_step_mm;
  std::size_t evaluations = 0;
};

// rest_drift_significant: the diagnosis's rest-drift verdict (rest_drift.hpp).
AxisChanges select_axis_changes(const ChangeFitData& data, const std::optional<core::StickSlipSpread>& spread, double noise_floor_mm,
                                bool rest_drift_significant);

}  // namespace epa::diag
