#pragma once
// Prints the simulated step metrics next to the paper's Table 1, as a commissioning engineer
// would compare them: one block per step size, one column pair (paper | sim) per controller.
#include <ostream>
#include <vector>

#include "report/simulation_case.hpp"

namespace epa::report {

void print_table1_comparison(std::ostream& out, const std::vector<SimulationCase>& cases);

}  // namespace epa::report
