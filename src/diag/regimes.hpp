#pragma once
// Where the gap lies: every sample of a run is labelled along a few dimensions (moving or at rest,
// direction, valve command near the dead band, position along the stroke, small or large move,
// transient or steady), and the windowed prediction error is summed per label. A regime whose
// share of the gap exceeds its share of the time is where the model is wrong; the residuals'
// autocorrelation and their cross-correlation with the valve command point at a cause.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/dead_zone.hpp"
#include "core/run.hpp"
#include "diag/windowed_gap.hpp"

namespace epa::diag {

// Thresholds of the labels (defaults suit the 500 mm cylinder at Ts = 5 ms).
struct RegimeOptions {
  double moving_mm_s = 15.0;          // |speed| (central difference over +-5 samples) above this: moving
  double deadband_margin_V = 0.25;    // valve within [b_l - margin, b_r + margin]: near the dead band
  double small_move_mm = 20.0;        // a motion with less travel than this is a small move
  double transient_s = 0.15;          // after a start, a stop or a valve step: transient for this long
  double valve_step_V = 0.5;          // a change of the command by more than this in one sample is a step
  double stroke_mm = 500.0;
};

// The dimensions and their regimes; each dimension partitions the samples.
inline constexpr std::size_t kDimensions = 6;
std::string_view dimension_name(std::size_t dimension);
const std::vector<std::string>& regime_names(std::size_t dimension);

struct SampleLabels {
  std::vector<std::array<std::uint8_t, kDimensions>> label;  // per sample k of the run
};
SampleLabels label_samples(const core::Run& run, const core::DeadZone& dead_zone, const RegimeOptions& options = {});

// Gap sums per regime of every dimension: sums[d][r].
struct RegimeSums {
  std::array<std::vector<GapSum>, kDimensions> sums;
  RegimeSums();
  void add(const WindowedReplay& replay, const SampleLabels& labels);
};

struct RegimeShare {
  std::string dimension, regime;
  double time_share_pct = 0, gap_share_pct = 0;
  double gap_mm = 0;  // RMS of the error within the regime
};
// Every regime with at least one sample, dimension by dimension; time shares of a dimension sum to 100.
std::vector<RegimeShare> shares(const RegimeSums& sums);

// Residual statistics of the pooled errors of one model.
struct ResidualStats {
  std::vector<double> autocorrelation;        // lags 1..max_lag
  std::vector<double> input_crosscorrelation; // corr(error(k), du(k - lag)), lags 0..max_lag; du = u(k) - u(k-1)
  std::size_t peak_input_lag = 0;             // lag of the largest |cross-correlation|
  double peak_input_correlation = 0;
};
ResidualStats residual_stats(const std::vector<const core::Run*>& runs, const std::vector<WindowedReplay>& replays,
                             std::size_t max_lag = 20);

// Plain-language pointers from the shares and residual statistics ("the gap lies at rest near the
// dead band: break points or friction").
std::vector<std::string> hints(const std::vector<RegimeShare>& shares, const ResidualStats& stats);

}  // namespace epa::diag
