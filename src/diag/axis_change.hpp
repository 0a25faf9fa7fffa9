#pragma once
// A change of a commissioned axis, as a change of its stick-slip model (core/stick_slip_params.hpp):
// friction up or down (both friction levels scaled), the flow gain (a supply or a valve: both
// speeds per volt scaled), the dead band moved (each break point shifted), the spool slower or
// faster (its lag), the line longer (the dead time). Each is named by the effect it is in the
// diagnosis's vocabulary (plant/effects.hpp), with its parameters in the model's own units.
#include <span>
#include <string>
#include <vector>

#include "core/stick_slip_params.hpp"
#include "plant/effects.hpp"

namespace epa::diag {

// The effects a commissioned stick-slip model can change by.
inline constexpr plant::EffectKind kAxisChanges[] = {plant::EffectKind::kStaticFriction, plant::EffectKind::kGainChange,
                                                     plant::EffectKind::kDeadzoneShift, plant::EffectKind::kValveLag,
                                                     plant::EffectKind::kInputDelay};

// One continuous parameter of a change, in its natural unit, with the search range.
struct ChangeParam {
  const char* name;  // as the report shows it: friction_ratio, flow_gain_ratio, shift_r_V, shift_l_V, spool_lag_s
  double neutral;    // no change (spool_lag_s: the commissioned lag)
  double lo, hi;
  bool log_scale;
  // The gap is jagged in it (a sticking model's friction: a breakaway a sample earlier or later),
  // so a fit of it alone scans its range before the local search (axis_change_fit.cpp).
  bool jagged = false;
};

// The continuous parameters of `kind` (input_delay has none: its dead time is searched whole).
std::vector<ChangeParam> change_params(plant::EffectKind kind, const core::StickSlipParams& commissioned);

// A set of changes with their values: `values[i]` lines up with change_params(kinds[i]); `delay_samples`
// is the dead time when kInputDelay is among them.
struct AxisChange {
  std::vector<plant::EffectKind> kinds;
  std::vector<std::vector<double>> values;
  int delay_samples = 0;
  bool has(plant::EffectKind kind) const;
  const std::vector<double>* values_of(plant::EffectKind kind) const;
};

// The commissioned model with the changes applied.
core::StickSlipParams apply_change(const core::StickSlipParams& commissioned, const AxisChange& change);
// The change of `kind` that takes `from` to `to` in that kind's terms (its inverse of apply_change):
// a model fitted from another one, described against the first.
AxisChange change_between(plant::EffectKind kind, const core::StickSlipParams& from, const core::StickSlipParams& to);

// Whether the change of `kind` lies beyond what the commissioned model's own uncertainty allows:
// beyond kSpreadMargin times the spread of its terms over parts of its identification runs, and
// beyond these floors (friction or gain ratio, a break point, the lag; the dead time by more than
// a sample). The spread is the largest of a handful of parts' fits: new runs of the same axis land
// beyond it about one time in (parts + 1) each way, beyond twice it rarely.
inline constexpr double kSpreadMargin = 2.0;
inline constexpr double kFrictionRatioTolerance = 0.2;
inline constexpr double kGainRatioTolerance = 0.08;
inline constexpr double kBreakToleranceV = 0.08;
inline constexpr double kLagToleranceS = 0.004;
bool beyond_tolerance(plant::EffectKind kind, const AxisChange& change, const core::StickSlipParams& commissioned,
                      const core::StickSlipSpread& spread);
// How far the change of `kind` lies from none, in the units the spread gives.
double change_size(plant::EffectKind kind, const AxisChange& change, const core::StickSlipParams& commissioned);

// The change in words: "friction up 140 %", "flow gain down 22 % (supply or valve)", ...
std::string describe_change(plant::EffectKind kind, const AxisChange& change, const core::StickSlipParams& commissioned);

}  // namespace epa::diag
