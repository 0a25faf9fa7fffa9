#pragma once
// What the closed-loop tests share: the paper's step sizes (its Figures 6-9) and the chatter count
// they judge a controller's rest by.
#include <cstddef>

#include "sim/closed_loop.hpp"

namespace epa::sim::testing {

inline constexpr double kPaperStepsMm[] = {25, 50, 100, 200};

// Valve sign changes in the last 10 s of a run: a controller at rest should not chatter.
inline std::size_t sign_changes_in_last_10s(const StepRun& r) { return valve_sign_changes_in_last(r, 10.0); }

}  // namespace epa::sim::testing
