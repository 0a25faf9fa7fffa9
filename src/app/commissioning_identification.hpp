#pragma once
// The commissioning sequence's identification step: `epa identify`'s pipeline on the excitation
// runs (all but the last estimate, the last validates).
#include "commission/commission_sequence.hpp"

namespace epa::app {

// `mm_per_volt` is the loop's sensor scale (the model's output y is in sensor volts).
commission::Identify identify_for_commissioning(double mm_per_volt);

}  // namespace epa::app
