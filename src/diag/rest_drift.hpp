#pragma once
// Readings that move while the model says the piston rests. With the valve inside the dead band
// for a while, every effect of the vocabulary leaves the piston still (a delayed, lagging,
// weakened or saturated drive is still no drive, and friction only holds it), so a steady motion of
// the readings there lies outside it: a sensor whose offset drifts, a leaking valve or seal, a load
// pushing the rod. The windowed gap cannot see it: each window restarts from the readings, and a
// drift of 1.5 mm/s moves 0.08 mm within a 10-sample window, less than the sensor's noise. So it
// is measured directly, as the least-squares speed of the readings over each rest.
#include <cstddef>
#include <vector>

#include "core/dead_zone.hpp"
#include "core/run.hpp"

namespace epa::diag {

struct RestDriftOptions {
  double margin_V = 0.1;          // the valve at least this far inside the break points
  double settle_s = 0.2;          // the model's own transient after entering the band (and a delay's)
  double min_rest_s = 0.2;        // what is left of a rest after settling must last this long
  std::size_t min_rests = 3;      // fewer rests than this: no judgement
  double min_speed_mm_s = 0.5;    // a median speed below this is never called motion
  double noise_factor = 4.0;      // nor one below this many times the noise's standard error of a rest's speed
  double outlier_sigmas = 5.0;    // readings this many noise deviations off a rest's line are outliers
};

struct RestDrift {
  std::size_t rests = 0;              // rests measured
  double median_speed_mm_s = 0;       // median over the rests of |least-squares speed|
  double threshold_mm_s = 0;          // the median speed noise alone stays below
  bool moving = false;                // enough rests, and their median speed above the threshold
};

// `dead_zone`: the break points the model uses (the fitted ones, when a shift is named);
// `noise_std_mm`: the sensor's noise (selection.hpp's estimate).
RestDrift rest_drift(const std::vector<const core::Run*>& runs, const core::DeadZone& dead_zone, double noise_std_mm,
                     const RestDriftOptions& options = {});

}  // namespace epa::diag
