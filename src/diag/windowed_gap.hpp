#pragma once
// The gap between a model and a recorded run: the windowed prediction error. Every `horizon`
// samples the model is restarted from the measured state (the ARX part's past outputs from the
// measured position, its past inputs from the recorded valve command through the model's input
// side) and run on the recorded valve command for `horizon` samples; each prediction is compared
// with the measurement. A plain open-loop replay would drift away, because the plant integrates.
//
// Effects that depend on the command history alone (delay, lag, dead zone, friction, gain,
// ceiling) are computed over the whole run, so they carry their state across restarts as the real
// valve would; position_dependent_gain reads where the piston is (its where_samples: the
// measured positions, then the model's own inside a window);
// sensor_quantization rounds the prediction as the sensor would round the truth.
//
// A window whose measurements (from the model's measured past to its last sample) come within
// kEndStopMarginMm of an end stop is left out: at a cushion the piston stops dead whatever the
// valve does, so those samples hold a collision that no effect in the vocabulary describes, and
// one run that hit a stop would otherwise dominate every fit (a blind rig: 7 mm of a 3 mm training
// gap from one run). The same windows are left out for every model, so gaps stay comparable.
#include <cstddef>
#include <span>
#include <vector>

#include "core/hammerstein_model.hpp"
#include "core/run.hpp"
#include "plant/effects.hpp"

namespace epa::diag {

// A model to replay: the nominal Hammerstein model with effects switched on.
struct ReplayModel {
  core::HammersteinModel model;
  plant::EffectSet effects;
  double stroke_mm = 500.0;  // end stops at 0 and stroke_mm
};

inline constexpr double kEndStopMarginMm = 1.0;

// Sum of squared prediction errors and their count: pools over runs, folds and regimes.
struct GapSum {
  double sse_mm2 = 0.0;
  std::size_t n = 0;
  std::size_t windows = 0;              // replayed
  std::size_t windows_at_end_stop = 0;  // left out (above)
  double rms_mm() const;
  GapSum& operator+=(const GapSum& o) {
    sse_mm2 += o.sse_mm2, n += o.n, windows += o.windows, windows_at_end_stop += o.windows_at_end_stop;
    return *this;
  }
};

// Every prediction of one run, in sample order.
struct WindowedReplay {
  std::vector<std::size_t> k;        // sample predicted
  std::vector<double> predicted_mm;  // what the model says the sensor reads there
  std::vector<double> error_mm;      // predicted - measured
  GapSum sum;
};

// Whether a reading in samples [from, to] lies within kEndStopMarginMm of an end stop (0 or stroke_mm).
bool touches_end_stop(const core::Run& run, std::size_t from, std::size_t to, double stroke_mm);

// The first sample a window may start at: the ARX part needs that much measured past.
std::size_t first_window_start(const core::HammersteinModel& model);

GapSum windowed_sse(const ReplayModel& model, const core::Run& run, std::size_t horizon);
WindowedReplay windowed_replay(const ReplayModel& model, const core::Run& run, std::size_t horizon);
// Pooled RMS over the runs, mm.
double windowed_gap_mm(const ReplayModel& model, std::span<const core::Run* const> runs, std::size_t horizon);

}  // namespace epa::diag
