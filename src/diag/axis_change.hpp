#pragma once
// A change of a commissioned axis, as a change of its stick-slip model (core/stick_slip_params.hpp):
// friction up or down (both friction levels scaled), the flow gain (both speeds per volt scaled),
// the supply (the air spring's frequency scaled, its wind-ups the other way), the dead band moved
// (each break point shifted), the spool slower or faster (its lag), the line longer (the dead
// time). Each term is named by the effect it is in the diagnosis's vocabulary (plant/effects.hpp),
// with its parameters in the model's own units.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "core/stick_slip_params.hpp"
#include "plant/effects.hpp"

namespace epa::diag {

// The terms a change is fitted in. The gain effect has two: the model holds a valve that passes
// less and a supply that dropped in different parameters. A lower supply hardly moves the speed
// (the exhausting side sets it) but softens the air spring, so the same friction force winds it
// further (notes/model-health.md: identified at 6 and 4.5 bar, the spring went 59 -> 42 rad/s,
// the wind-ups x1.44, the speed x0.96).
enum class ChangeTerm { kFriction, kFlowGain, kSupply, kDeadBand, kSpoolLag, kDeadTime };
inline constexpr std::size_t kChangeTermCount = 6;
inline std::size_t index(ChangeTerm term) { return static_cast<std::size_t>(term); }
plant::EffectKind effect_of(ChangeTerm term);
// The term whose tolerance (floor and spread) `term` is held to: the supply to friction's, since it
// scales the wind-ups as friction does; every other term to its own.
inline ChangeTerm tolerance_term(ChangeTerm term) { return term == ChangeTerm::kSupply ? ChangeTerm::kFriction : term; }

// The terms the diagnosis selects changes among: one per effect, those the commissioned model's
// spread (epa identify) covers.
inline constexpr ChangeTerm kAxisChanges[] = {ChangeTerm::kFriction, ChangeTerm::kFlowGain, ChangeTerm::kDeadBand,
                                              ChangeTerm::kSpoolLag, ChangeTerm::kDeadTime};

// One continuous parameter of a change, in its natural unit, with the search range.
struct ChangeParam {
  const char* name;  // as the report shows it: friction_ratio, flow_gain_ratio, spring_frequency_ratio, shift_r_V, shift_l_V, spool_lag_s
  double neutral;    // no change (spool_lag_s: the commissioned lag)
  double lo, hi;
  bool log_scale;
  // The gap is jagged in it (a sticking model's friction: a breakaway a sample earlier or later),
  // so a fit of it alone scans its range before the local search (axis_change_fit.cpp).
  bool jagged = false;
};

// The continuous parameters of `term` (the dead time has none: it is searched whole).
std::vector<ChangeParam> change_params(ChangeTerm term, const core::StickSlipParams& commissioned);

// A set of changes with their values: `values[i]` lines up with change_params(terms[i]); `delay_samples`
// is the dead time when kDeadTime is among them.
struct AxisChange {
  std::vector<ChangeTerm> terms;
  std::vector<std::vector<double>> values;
  int delay_samples = 0;
  bool has(ChangeTerm term) const;
  const std::vector<double>* values_of(ChangeTerm term) const;
};

// The commissioned model with the changes applied.
core::StickSlipParams apply_change(const core::StickSlipParams& commissioned, const AxisChange& change);
// The change of `term` that takes `from` to `to` (its inverse of apply_change): a model fitted from
// another one, described against the first.
AxisChange change_between(ChangeTerm term, const core::StickSlipParams& from, const core::StickSlipParams& to);

// Whether the change of `term` lies beyond what the commissioned model's own uncertainty allows:
// beyond kSpreadMargin times the spread of its terms over parts of its identification runs, and
// beyond these floors (friction or gain ratio, a break point, the lag; the dead time by more than
// a sample); the supply to friction's (tolerance_term). The spread is the largest of a handful of
// parts' fits: new runs of the same axis land beyond it about one time in (parts + 1) each way,
// beyond twice it rarely.
inline constexpr double kSpreadMargin = 2.0;
inline constexpr double kFrictionRatioTolerance = 0.2;
inline constexpr double kGainRatioTolerance = 0.08;
inline constexpr double kBreakToleranceV = 0.08;
inline constexpr double kLagToleranceS = 0.004;
bool beyond_tolerance(ChangeTerm term, const AxisChange& change, const core::StickSlipParams& commissioned,
                      const core::StickSlipSpread& spread);
// How far the change of `term` lies from none, in the units the spread gives (the supply: the
// log of its frequency ratio, as friction's).
double change_size(ChangeTerm term, const AxisChange& change, const core::StickSlipParams& commissioned);

// The change in words: "friction up 140 %", "flow gain down 22 % (supply or valve)",
// "air spring softer: 59 -> 42 rad/s (supply pressure down)", ...
std::string describe_change(ChangeTerm term, const AxisChange& change, const core::StickSlipParams& commissioned);

}  // namespace epa::diag
