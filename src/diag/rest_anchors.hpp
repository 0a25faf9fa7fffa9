#pragma once
// Where a recorded run's state is known: the piston at rest. A model restarted from noisy readings
// inherits their noise through its own poles (an integrating model turns 0.1 mm of noise into mm
// of predicted motion); a piston that stands has speed zero and a position known to the mean of
// many readings. The gap measured from there (from_rest_gap.hpp) has a floor set by the sensor
// alone, and runs over a whole move: the scale on which a user sees a model's error.
//
// A sample is at rest when the readings of the kRestWindow samples up to it lie on a line flatter
// than kRestSpeedMmS (or four of its standard errors under the noise, whichever is larger) and
// scatter about it by no more than the noise allows. A rest's anchor is kAnchorMargin samples
// before its last sample, so that a motion the window has not yet seen is not in the mean.
#include <cstddef>
#include <vector>

#include "core/run.hpp"

namespace epa::diag {

inline constexpr std::size_t kRestWindow = 40;     // 0.2 s at 5 ms
inline constexpr std::size_t kAnchorMargin = 10;   // 50 ms: a breakaway the window has not yet seen
inline constexpr double kRestSpeedMmS = 1.0;
inline constexpr std::size_t kStartReadings = 4;  // a run's first readings that must be flat for it to start at rest

struct RestAnchor {
  std::size_t k = 0;          // the sample the model restarts at
  double position_mm = 0.0;   // the mean of the readings before it
  std::size_t readings = 0;   // how many readings that mean holds
};

struct RestSpan {
  std::size_t first = 0, last = 0;  // samples whose readings stand (inclusive)
};

struct RestAnchors {
  std::vector<RestAnchor> anchors;  // in sample order
  std::vector<RestSpan> spans;      // every stretch at rest, also those too short for an anchor
  double noise_std_mm = 0.0;        // the readings' scatter about their line at rest
};

// The run's sensor noise: the 20th percentile of the scatter about a line over windows of
// kRestWindow samples (most of a run's windows hold a piston at rest or moving smoothly).
double reading_noise_mm(const core::Run& run);

// Rests in the run, each at least kRestWindow + kAnchorMargin samples long, and its start when
// its first kStartReadings readings are flat.
RestAnchors rest_anchors(const core::Run& run);

}  // namespace epa::diag
