#pragma once
// The stability verdict a controller must pass before it is stored: Jury on every branch of the
// dead-zone compensation (control/pole_placement_design.hpp). `epa design --save` and
// `epa tuning import` refuse with it alike (exit 3).
#include <string>
#include <vector>

#include "control/pole_placement_design.hpp"

namespace epa::control {

// "" when no branch is unstable (a marginal one, a root on the circle, is reported by the design
// but not refused), else the unstable ones: "left (max |root| 1.53), right (max |root| 1.71)".
std::string unstable_branches(const std::vector<ClosedLoopBranch>& branches);

}  // namespace epa::control
