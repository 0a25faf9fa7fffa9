#pragma once
// A coarse position sensor is seen in the readings themselves: they lie on a grid. A windowed
// replay cannot predict which way a reading rounds, so quantisation never shrinks the prediction
// gap; it raises the floor the gap can reach. The diagnosis names sensor_quantization when the
// readings lie on a grid and that grid's rounding error accounts for the gap left.
#include <optional>
#include <vector>

#include "core/run.hpp"

namespace epa::diag {

// The step of the grid the readings lie on (mm), or nothing when they do not lie on one: at least
// 99 % of the readings of every run within 1 % of a step from a multiple of it (counted from the
// run's first reading), with at least 10 levels visited.
std::optional<double> reading_resolution_mm(const std::vector<const core::Run*>& runs);

}  // namespace epa::diag
