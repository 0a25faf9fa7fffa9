#pragma once
// The gap over whole moves: a model run free on the recorded valve command, its position set to
// the readings' mean wherever the piston rests (rest_anchors.hpp) and its speed to zero, and
// compared with every reading up to kFromRestSpanS after that (or to the next rest). What the
// model carries across a rest (the spool, the air spring's wind-up, the command in transit) stays
// its own, as a valve and a cylinder keep theirs. Its noise floor is the sensor's, whatever the
// model's poles: nothing noisy is pushed through them.
//
// A segment whose readings come within kEndStopMarginMm of an end stop is left out, as in the
// windowed gap: a collision no model term describes. So is one whose valve command leaves the
// range the model was identified on (JudgedScope): there the model extrapolates, and its error is
// not a change of the axis.
#include <cstddef>
#include <span>
#include <vector>

#include "core/hammerstein_model.hpp"
#include "core/run.hpp"
#include "core/stick_slip_params.hpp"
#include "diag/rest_anchors.hpp"
#include "diag/windowed_gap.hpp"

namespace epa::diag {

inline constexpr double kFromRestSpanS = 4.0;

// Where segments are judged.
struct JudgedScope {
  double stroke_mm = 500.0;  // end stops at 0 and here
  double drive_lo_v = -1e9, drive_hi_v = 1e9;  // the valve commands the model was identified on
  double span_s = kFromRestSpanS;               // each segment at most this long after its rest
  static constexpr double kDriveToleranceV = 0.05;
  bool drive_inside(double u_V) const { return u_V >= drive_lo_v - kDriveToleranceV && u_V <= drive_hi_v + kDriveToleranceV; }
};

// A run with its rests, found once.
struct AnchoredRun {
  const core::Run* run = nullptr;
  RestAnchors rests;
};
std::vector<AnchoredRun> anchor_runs(std::span<const core::Run* const> runs);

// Every prediction of one run (the samples the gap counts), in sample order.
struct FreeRunTrace {
  std::vector<std::size_t> k;
  std::vector<double> predicted_mm;
  std::vector<bool> stuck;  // the stick-slip model's piston sticks there (empty for the Hammerstein model)
  GapSum sum;  // windows: segments judged; windows_at_end_stop: segments left out (end stop or drive range)
};

// The gap of the Hammerstein model (its dead zone and ARX part) and of the stick-slip model.
GapSum from_rest_sse(const core::HammersteinModel& model, const AnchoredRun& run, const JudgedScope& scope);
GapSum from_rest_sse(const core::StickSlipParams& params, double Ts, const AnchoredRun& run, const JudgedScope& scope);
FreeRunTrace from_rest_trace(const core::StickSlipParams& params, double Ts, const AnchoredRun& run, const JudgedScope& scope);
FreeRunTrace from_rest_trace(const core::HammersteinModel& model, const AnchoredRun& run, const JudgedScope& scope);

// Pooled RMS over the runs, mm.
double from_rest_gap_mm(const core::HammersteinModel& model, std::span<const AnchoredRun> runs, const JudgedScope& scope);
double from_rest_gap_mm(const core::StickSlipParams& params, double Ts, std::span<const AnchoredRun> runs, const JudgedScope& scope);

// What the gap of a perfect model would be with sensor noise of noise_std_mm: the readings' noise
// about the truth, and the noise of the mean each restart starts from, mm.
double from_rest_noise_floor_mm(std::span<const AnchoredRun> runs, double noise_std_mm);

}  // namespace epa::diag
