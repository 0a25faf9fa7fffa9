#pragma once
// Fits the stick-slip model (plant/stick_slip_model.hpp) to open-loop runs on the simulation error:
// each segment is simulated from rest at its first measured position on the recorded command
// alone, and the mean squared position error over all samples is minimised (BOBYQA, NLopt, over
// the nine continuous parameters, mapped to a unit box: break points linear, the rest on a log
// scale), then the dead time is chosen among 0..2 samples around it.
//
// Why a second model beside the Hammerstein one. On a pneumatic axis the Hammerstein model's
// free-run fit stays near 55-80 % (docs/identification.md): how far a pulse moves the piston
// depends on what the last move left in the chambers, and a static dead zone on a linear model
// cannot hold that. The stick-slip model holds it in one state (the air spring's wind-up) and
// fits such runs above 90 %. The pole-placement design still takes the Hammerstein model (it
// needs a linear model); this one is what a simulation of the axis should run.
//
// The start comes from the Hammerstein fit (its break points and speeds per volt), so the fit
// starts where the data already point; the other parameters start at a pneumatic cylinder's
// typical values and are free within wide bounds.
#include <cmath>
#include <cstddef>
#include <vector>

#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "ident/ident_data.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::ident {

struct StickSlipFitOptions {
  double Ts = 0.005;                // s
  double mm_per_volt = 50.0;        // the segments' y is in sensor volts
  unsigned evaluations_per_start = 3000;
  unsigned starts = 12;             // the given start, then others over friction, spring and speed (a grid of 12)
  int substeps = 2;                 // of the model's integration

  core::Status validate() const;
};

struct StickSlipFit {
  plant::StickSlipParams params;
  double loss_mm2 = 0.0;        // mean squared simulation error on the estimation segments
  std::size_t evaluations = 0;  // simulations run
};

// The start from an identified Hammerstein model: the flow's break points a little inside its
// (which are where the piston starts to move, friction included), its speeds per volt, its dead
// time less the sample every ARX model has, and a pneumatic cylinder's typical spring and friction.
plant::StickSlipParams stick_slip_start(const core::HammersteinModel& model, std::size_t nk);

// Errors: invalid options, no segment, a start that does not validate.
core::Result<StickSlipFit> fit_stick_slip(const std::vector<Segment>& segments, const plant::StickSlipParams& start,
                                          const StickSlipFitOptions& options);

// The whole step as `epa identify` takes it: started from the Hammerstein model, fitted on the
// estimation segments, scored on both (pooled NRMSE fit of the free run, arx_metrics.hpp), and
// the commands at which the fitted model's piston starts to move on a slow ramp each way.
struct StickSlipIdentification {
  StickSlipFit fit;
  double estimation_pct = 0.0;
  double validation_pct = NAN;          // NaN without validation segments
  double ramp_right_v = NAN, ramp_left_v = NAN;
  static constexpr double kRampVPerS = 0.1;  // the slow ramp of those two figures
};
core::Result<StickSlipIdentification> identify_stick_slip(const std::vector<Segment>& estimation,
                                                          const std::vector<Segment>& validation,
                                                          const core::HammersteinModel& start_model, std::size_t nk,
                                                          const StickSlipFitOptions& options);

// Each segment simulated from rest at the mean of its first 5 readings; positions in sensor volts
// (as the segments' y), for nrmse_fit_percent (arx_metrics.hpp).
std::vector<std::vector<double>> simulate_stick_slip(const std::vector<Segment>& segments,
                                                     const plant::StickSlipParams& params, double Ts,
                                                     double mm_per_volt, int substeps = 2);

}  // namespace epa::ident
