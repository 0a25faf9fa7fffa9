#pragma once
// The shapes of the effects a diagnosis names, in physical units, for the HTML report: a reader
// sees what was fitted (gain along the stroke each way, the drive friction leaves, the spool's
// step response, the dead zone moved), not only its parameters.
#include <vector>

#include "diag/selection.hpp"
#include "report/svg_chart.hpp"

namespace epa::report {

// One panel per named effect that has a shape (sensor_quantization has none worth drawing),
// from the diagnosis's final model against the nominal one.
std::vector<Panel> effect_shape_panels(const diag::Diagnosis& diagnosis);

}  // namespace epa::report
