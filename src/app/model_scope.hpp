#pragma once
// Where an identified model holds, as epa identify and epa commission both record it beside the
// model: the valve commands its estimation runs covered (outside them it extrapolates), and how far
// its stick-slip terms move when re-fitted on parts of the validation runs
// (diag/stick_slip_spread.hpp). epa diagnose judges the model inside the first and names a change
// of the axis only beyond the second.
#include <array>
#include <span>

#include "core/run.hpp"
#include "core/stick_slip_params.hpp"

namespace epa::app {

// V: the lowest and the highest command of the runs, 0 included.
std::array<double, 2> identified_drive_v(std::span<const core::Run* const> estimation);

core::StickSlipSpread model_spread(const core::StickSlipParams& params, double Ts, std::span<const core::Run* const> validation,
                                   const std::array<double, 2>& drive_v);

}  // namespace epa::app
