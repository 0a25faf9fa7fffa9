#pragma once
// Step-response metrics with MATLAB stepinfo conventions (docs/paper.md): rise time 10-90 % and a
// 2 % settling band, both against the final value; overshoot against the final value; the
// steady-state error is the mean |r - y| over the last window (2 s of a 20 s run).
// "Never reached" is std::nullopt, never a large number.
#include <optional>
#include <span>

namespace epa::core {

struct StepMetricsOptions {
  double Ts = 0.005;              // sample time of y, s
  double ess_window_s = 2.0;      // window at the end for the steady-state error and final value
  double settling_band = 0.02;    // settling band as a fraction of the move
  double rise_low = 0.10, rise_high = 0.90;
};

struct StepMetrics {
  std::optional<double> rise_s;        // nullopt: never got from 10 % to 90 % of the move
  std::optional<double> settling_s;    // nullopt: still outside the band at the last sample
  std::optional<double> overshoot_pct; // nullopt: the piston never moved (no move to compare with)
  double ess_mm = 0.0;                 // mean |r - y| over the last window
  double final_mm = 0.0;               // final value: mean of y over the last window
  bool moved = false;                  // the final value left the start by more than the band
};

// y_mm[0] is the position at the step (k = 0, when the reference changes to r_mm).
// The final value is the mean over the last window rather than the last sample alone, so that
// sensor noise does not decide the band; for a settled, noise-free run the two agree.
// A response counts as having moved when |final - y0| exceeds settling_band * |r - y0|;
// otherwise rise, settling and overshoot are nullopt (plain PP stalled in the dead zone).
StepMetrics step_metrics(std::span<const double> y_mm, double r_mm, const StepMetricsOptions& options = {});

}  // namespace epa::core
