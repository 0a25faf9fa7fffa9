#pragma once
// Fitting an effect's 1-3 parameters on training runs: the windowed gap (windowed_gap.hpp) is the
// loss. Continuous parameters by NLopt's BOBYQA within the bounds of plant::param_specs, from a
// few starts; the integer delay on a grid of every value; the sensor step on a geometric grid
// then a finer one (the loss is piecewise constant in it, which a local search cannot follow).
// The effects already in the base model keep their parameters.
#include <span>
#include <vector>

#include "core/run.hpp"
#include "diag/windowed_gap.hpp"
#include "plant/effects.hpp"

namespace epa::diag {

struct FitOptions {
  std::size_t horizon = 10;
  unsigned max_evaluations_per_start = 150;
  // Also fit the members fitted last (ParamSpec::fitted_last: gain_change's drift), which
  // otherwise stay where they stand while neutral.
  bool fit_last = false;
};

struct EffectFit {
  ReplayModel model;          // base with the fitted effects switched on
  double train_gap_mm = 0.0;  // pooled windowed gap on the training runs
  std::size_t evaluations = 0;
};

// Fits `kinds` jointly (their parameters together) on top of `base`.
EffectFit fit_effects(const ReplayModel& base, std::span<const plant::EffectKind> kinds,
                      std::span<const core::Run* const> runs, const FitOptions& options);
inline EffectFit fit_effect(const ReplayModel& base, plant::EffectKind kind, std::span<const core::Run* const> runs,
                            const FitOptions& options) {
  return fit_effects(base, std::span<const plant::EffectKind>(&kind, 1), runs, options);
}

// The nominal model's own parameters re-fitted: drive gain and both break points
// (gain_change + deadzone_shift), because on a real rig much of a gap is parameters that are off.
EffectFit refit_nominal(const ReplayModel& base, std::span<const core::Run* const> runs, const FitOptions& options);

}  // namespace epa::diag
