#pragma once
// Fits a change of a commissioned axis (axis_change.hpp) on the training runs' gap over whole
// moves (from_rest_gap.hpp), and scores it on the held-out runs.
#include <cstddef>
#include <span>
#include <vector>

#include "core/stick_slip_params.hpp"
#include "diag/axis_change.hpp"
#include "diag/from_rest_gap.hpp"

namespace epa::diag {

struct ChangeFit {
  AxisChange change;
  double train_gap_mm = 0.0;
  double heldout_gap_mm = 0.0;
  std::size_t evaluations = 0;
};

struct ChangeFitData {
  core::StickSlipParams commissioned;
  double Ts = 0.005;
  std::span<const AnchoredRun> train, heldout;
  JudgedScope scope;
};

// The changes of `terms` fitted together, each continuous value started from `start` where it
// holds that term, else from no change; the dead time, when among them, searched whole over
// 0..StickSlipParams::kMaxDelay with the rest fitted at each.
ChangeFit fit_change(const ChangeFitData& data, const std::vector<ChangeTerm>& terms, const AxisChange& start = {});

}  // namespace epa::diag
