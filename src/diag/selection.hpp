#pragma once
// Which effect explains the gap, and how far it shrinks: the diagnosis. Its steps, as diagnose()
// takes them (selection.cpp numbers its step functions the same):
//
//  1. measure_baseline: the nominal model's held-out windowed gap (and the training gap).
//  2. refit_nominal_parameters: the nominal model's own parameters (drive gain, its steady speed
//     within the printed B's precision, both break points) fitted on the training runs and scored
//     held out; they stay free in every later fit, since on a rig much of a gap is parameters that
//     are off, and an effect fitted on wrong parameters is biased.
//  3. estimate_noise_floor: the gap that sensor noise alone gives a perfect model, estimated from
//     the runs at rest, and never below min_floor_mm.
//  4. select_forward: every structural effect (delay, lag, friction, ceiling, position dependence,
//     quantisation) fitted with the nominal parameters on the training runs and scored held out
//     (the first round: the candidate table); then the effect with the largest held-out reduction
//     is added while that reduction beats its chance threshold (the reduction fitting that effect
//     gives on effect-free data: chance_threshold.hpp) and the gap before it lies above the noise
//     floor (below it a fit only takes noise away), re-fitting on top of what is accepted; at most
//     max_effects. input_delay and valve_lag explain much the same; when the runner-up comes
//     within confusable_ratio of the winner's reduction, the pair is reported as confusable.
//  5. try_pairs: the best pair_pool first-round candidates fitted two at a time, jointly (from the
//     better one fitted alone, the other added afresh, so no pair leaves more than it); a pair
//     replaces the forward set when it leaves a smaller gap and each of its effects beats its own
//     chance threshold on top of the other (two effects that each explain little alone).
//  6. refit_jointly_then_check_backward: the accepted set re-fitted jointly (all free at once, from
//     where the selection left them and from neutral), then a backward check: an effect stays only
//     while removing it (the rest re-fitted from where they stand) costs more than its chance
//     threshold.
//  7. drop_effects_that_do_nothing: an effect fitted to its neutral values, or whose switching off
//     moves the held-out gap by less than half a percent, is not named.
//  8. fit_gain_drift_last: a gain that drifts during each run (a sagging supply), fitted last beside
//     the accepted effects, kept when it beats the gain's chance threshold.
//  9. name_nominal_parameters: gain_change and deadzone_shift are named when their parameters,
//     fitted with the accepted effects, lie beyond tolerances calibrated on effect-free data from
//     slightly perturbed models and holding them nominal costs more than their chance threshold
//     of the baseline gap (a parameter that only absorbs the residue of an effect's imperfect form
//     is not a finding). Beside a position dependence a gain that holds is that dependence's level
//     (the runs cannot tell the two apart): it is said, not named; a gain that drifts is named.
// 10. complete_candidate_table: the nominal parameters scored alone beside the first round.
// 11. check_rest_drift: readings that move while the valve rests inside the dead band
//     (rest_drift.hpp) leave the gap unexplained: no effect of the vocabulary moves a piston
//     there, and the windowed gap is blind to a slow drift. Otherwise the gap is unexplained when
//     it lies above unexplained_factor times the noise floor and, when effects are named, above
//     unexplained_share of the baseline gap: a rig's effect never has the library's exact form,
//     and the residue of the named effects' forms is theirs.
// 12. account_for_sensor_resolution: readings on a grid coarser than the noise name
//     sensor_quantization and raise the noise floor to what the rounding leaves.
// Without held-out runs, folds leave one training run out each (cross-validation by run).
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/run.hpp"
#include "diag/effect_fit.hpp"
#include "diag/rest_drift.hpp"
#include "diag/windowed_gap.hpp"
#include "plant/effects.hpp"

namespace epa::diag {

struct DiagnosisOptions {
  std::size_t horizon = 10;
  std::vector<plant::EffectKind> candidates{plant::kAllEffects.begin(), plant::kAllEffects.end()};
  std::size_t max_effects = 3;
  double threshold_scale = 1.0;    // multiplies every chance threshold
  double confusable_ratio = 0.85;
  double unexplained_factor = 1.6;
  // The noise floor is never below this: under 10 um a gap is finer than any position sensor of a
  // pneumatic axis (the shipped ADC's count is 15 um), and the run files' own digits (0.1 um, 10 uV
  // of valve command) leave a few um on noise-free recordings, which no effect is to be named for.
  double min_floor_mm = 0.01;
  double unexplained_share = 1.0 / 3.0;  // with effects named: a gap left above this share of the baseline
  std::size_t pair_pool = 4;             // the best first-round candidates tried in pairs
  double refit_threshold_pct = 5.0;  // the re-fit must beat this reduction for gain/break points to be named
  double gain_tolerance = 0.06;      // |gain_ratio - 1| beyond this names gain_change
  double shift_tolerance_V = 0.06;   // a break point moved beyond this names deadzone_shift
  std::function<void(const std::string&)> progress;  // one line per stage; empty: quiet
};

struct Fold {
  std::vector<const core::Run*> train, test;
};

struct CandidateScore {
  plant::EffectKind kind;
  plant::EffectParams params{};   // fitted on all training runs, alone on the nominal model
  double heldout_gap_mm = 0;
  double reduction_pct = 0;       // against the baseline
  double reduction_vs_refit_pct = 0;  // against the re-fitted nominal model (what acceptance uses)
  double threshold_pct = 0;       // its chance threshold
  bool accepted = false;          // in the verdict
};

struct SelectionStep {
  plant::EffectKind kind;
  double gap_before_mm = 0, gap_after_mm = 0, reduction_pct = 0, threshold_pct = 0;
  bool accepted = false;
};

struct Diagnosis {
  std::size_t horizon = 10;
  ReplayModel nominal, refit, final_model;   // final: nominal with the accepted effects (all training runs)
  double baseline_gap_mm = 0, refit_gap_mm = 0, final_gap_mm = 0;  // held-out (pooled over folds)
  double train_gap_mm = 0;                   // nominal, on the training runs
  std::size_t windows_at_end_stop = 0;       // left out of every gap (windowed_gap.hpp), all runs
  std::size_t windows = 0;                   // all windows of all runs, those included
  std::vector<CandidateScore> candidates;    // best first
  std::vector<SelectionStep> steps;          // the forward selection, in order
  std::vector<plant::EffectKind> effects;    // accepted, in order
  std::vector<std::pair<plant::EffectKind, plant::EffectKind>> confusable;
  double noise_std_mm = 0, noise_floor_mm = 0;
  RestDrift rest_drift;                      // readings that move while the final model rests
  bool unexplained = false;
  bool cross_validated = false;
  std::size_t evaluations = 0;
};

// Folds: one with `heldout` as test when it is non-empty, else leave-one-run-out over `train`
// (which then needs at least 2 runs; checked by the caller).
std::vector<Fold> make_folds(const std::vector<const core::Run*>& train, const std::vector<const core::Run*>& heldout);

Diagnosis diagnose(const ReplayModel& nominal, const std::vector<const core::Run*>& train,
                   const std::vector<const core::Run*>& heldout, const DiagnosisOptions& options);

// Sensor noise (mm, one standard deviation) from second differences of the position at rest
// with the valve inside the dead band.
double estimate_noise_std_mm(const std::vector<const core::Run*>& runs, const core::DeadZone& dead_zone);
// RMS windowed gap that white sensor noise of `noise_std_mm` gives a perfect model.
double noise_floor_mm(const core::HammersteinModel& model, double noise_std_mm, std::size_t horizon);

}  // namespace epa::diag
