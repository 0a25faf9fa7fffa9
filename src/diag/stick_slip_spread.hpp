#pragma once
// How far a stick-slip model's terms move when it is re-fitted on parts of the runs it was
// identified on (core::StickSlipSpread): each part of kSpreadPartS, and each change of
// axis_change.hpp fitted alone on it. epa identify writes it beside the model, so that epa
// diagnose names a change only when it is larger than the model's own disagreement with some
// regime of motion it was identified on.
#include <span>

#include "core/run.hpp"
#include "core/stick_slip_params.hpp"
#include "diag/from_rest_gap.hpp"

namespace epa::diag {

inline constexpr double kSpreadPartS = 15.0;

// Parts shorter than kSpreadPartS at a run's end are folded into the part before.
core::StickSlipSpread stick_slip_spread(const core::StickSlipParams& params, double Ts, std::span<const core::Run* const> runs,
                                        const JudgedScope& scope);

}  // namespace epa::diag
