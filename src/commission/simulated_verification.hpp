#pragma once
// The commissioning sequence's check before anything reaches the axis: the designed law against
// the identified model and against that model perturbed (gain -+, dead band wider and narrower),
// on the spec's verification moves: the identified model's by the spec's limits, the perturbed
// ones by its robust_limits. When identification found that a stick-slip model describes the axis
// (core::AxisModel), the moves run on that model and its perturbations instead: a law that would
// hunt on the axis hunts there too, before it reaches the axis.
#include <optional>
#include <string>
#include <vector>

#include "commission/commission_spec.hpp"
#include "commission/move_acceptance.hpp"
#include "control/controller.hpp"
#include "core/hammerstein_model.hpp"
#include "core/stick_slip_params.hpp"


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
// `axis` (the stick-slip model that describes the axis, if one does) replaces `model` as the plant;
// its gain is its speeds per volt, its dead band its flow break points.
SimulatedVerification verify_in_simulation(const core::HammersteinModel& model, const std::optional<core::StickSlipParams>& axis,
                                           const control::ControllerParams& params, const CommissionSpec& spec, double start_mm);

}  // namespace epa::commission
