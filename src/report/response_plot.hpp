#pragma once
// The picture of `epa simulate`: for each step size, the piston position of every controller
// against the reference (paper figures 7-10) and the valve command with the dead band shaded
// (figures 11-13), as a standalone SVG a person opens in a browser.
#include <string>
#include <vector>

#include "core/dead_zone.hpp"
#include "report/simulation_case.hpp"

namespace epa::report {

std::string render_response_plot(const std::vector<SimulationCase>& cases, const core::DeadZone& dead_zone,
                                  double window_s, const std::string& title);

}  // namespace epa::report
