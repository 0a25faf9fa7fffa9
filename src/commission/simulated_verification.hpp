#pragma once
// The commissioning sequence's check before anything reaches the axis: the designed law against
// the identified model and against that model perturbed (gain -+, dead band wider and narrower),
// on the spec's verification moves: the identified model's by the spec's limits, the perturbed
// ones by its robust_limits.
#include <string>
#include <vector>

#include "commission/commission_spec.hpp"
#include "commission/move_acceptance.hpp"
#include "control/controller.hpp"
#include "core/hammerstein_model.hpp"


namespace epa::commission {

struct SimulatedCase {
  std::string name;  // "identified", "gain x0.8", "dead band +0.1 V", ...
  std::vector<JudgedMove> moves;
  std::vector<std::vector<double>> positions_mm;  // each move's simulated response, one per sample
  bool passed = false;
};

struct SimulatedVerification {
  std::vector<SimulatedCase> cases;  // the identified model first
  bool passed = false;
  std::string why;  // the first failure: case and move
};

// The moves start at rest at `start_mm`. The law keeps `params` (designed for `model`) in every case.
SimulatedVerification verify_in_simulation(const core::HammersteinModel& model, const control::ControllerParams& params,
                                           const CommissionSpec& spec, double start_mm);

}  // namespace epa::commission
