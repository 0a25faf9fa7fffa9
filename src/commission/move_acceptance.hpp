#pragma once
// Whether one verification move is good enough: the same judgement for a move simulated on the
// identified model and for a move made on the axis.
#include <string>

#include "commission/commission_spec.hpp"
#include "core/step_metrics.hpp"

namespace epa::commission {

struct JudgedMove {
  double from_mm = 0.0, to_mm = 0.0;
  core::StepMetrics metrics;
  bool passed = false;
  std::string why;  // the first limit it broke, in words; empty when it passed
};

JudgedMove judge_move(double from_mm, double to_mm, const core::StepMetrics& metrics, const MoveLimits& limits);

}  // namespace epa::commission
