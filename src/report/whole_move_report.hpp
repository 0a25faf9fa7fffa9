#pragma once
// The HTML report's section on the gap over whole moves (diag/whole_move.hpp): the first scored
// run with both models run free from its rests and where the piston stands, the stick-slip
// model's friction against speed in physical units, the terms it adds and what changed since
// commissioning.
#include <string>

#include "diag/gap_report.hpp"

namespace epa::report {

// Empty when the report has no whole-move gap.
std::string render_whole_move_html(const diag::GapReport& report);

}  // namespace epa::report
