#pragma once
// One whole commissioning run, offline, on tests/integration/commission_test.py's rig: the physics
// plant with its hidden perturbations (orifice 3.2 mm2, spool overlap +1.4/-1.5 V) behind a
// late-command I/O path (physics_rig_axis.hpp), the test's spec (pp-traj, limits 1 mm, 5 %). Before
// commissioning the axis makes the test's ten HMI moves with the paper's tuning: the chambers'
// pressures a working axis has, which the excitation's response depends on (from a fresh 3 bar in
// both chambers the identified models followed their held-out runs 15-25 points worse than those
// the real appliance identifies on that rig). About 5 s a run; no real time.
#include <atomic>

#include "app/commissioning_identification.hpp"
#include "commission/commission_sequence.hpp"
#include "commission/commission_spec.hpp"
#include "core/paper_reference.hpp"
#include "physics_rig_axis.hpp"
#include "plant/pneumatic_params.hpp"

namespace epa::testing {

// `late_probability`: that a command reaches the valve a cycle late; `seed`: the sensor noise's and
// the I/O path's. Errors: the spec does not parse, or an HMI move failed (a harness error).
inline core::Result<commission::CommissionOutcome> commission_physics_rig(std::uint64_t seed, double late_probability) {
  static constexpr const char* kSpec = R"({"excitation_runs": 2, "excitation_s": 40, "seed": 3, "controller": "pp-traj",
    "settling_s": 0.3, "overshoot_pct": 0, "moves_mm": [150, 350, 250, 225, 275], "move_hold_s": 6, "name": "rig-1",
    "limits": {"ess_mm": 1, "overshoot_pct": 5, "overshoot_mm": 0, "settling_s": 0}})";
  static constexpr double kHmiTargetsMm[] = {225, 275, 175, 275, 125, 325, 250, 50, 250, 450};
  const auto spec = commission::parse_commission_spec(kSpec);
  if (!spec) return spec.error();
  plant::PneumaticParams rig;
  rig.orifice_area_mm2 = 3.2, rig.overlap_pos_v = 1.4, rig.overlap_neg_v = -1.5;
  const auto paper = paper_running_tuning();
  PhysicsRigAxis axis(rig, seed, late_probability, paper);
  const std::atomic<bool> no_abort{false};
  for (double target : kHmiTargetsMm)
    if (auto moved = axis.move(target, 5.0, no_abort); !moved) return moved.error();
  axis.stop();
  commission::CommissionSequence sequence(axis, app::identify_for_commissioning(paper.model.model.mm_per_volt));
  return sequence.run(*spec);
}

}  // namespace epa::testing
