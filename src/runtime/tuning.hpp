#pragma once
// A tuning set ready for the loop: validated parameters of all four laws from one base
// configuration, so switching the controller is a lookup at a cycle boundary, never a rebuild.
#include "control/controller.hpp"
#include "runtime/runtime_config.hpp"

namespace epa::runtime {

struct Tuning {
  control::ControllerParams pp, ngidz, ffidz, traj;
  // False when pp-traj cannot run on this set's model (it needs one that integrates); the other
  // three laws stay usable and selecting pp-traj is refused. A flag, not the reason: the loop
  // copies a Tuning on every swap and must not allocate (ControllerParams::make says why).
  bool traj_available = true;

  const control::ControllerParams& for_kind(control::ControllerKind kind) const noexcept {
    switch (kind) {
      case control::ControllerKind::kPp: return pp;
      case control::ControllerKind::kPpNgidz: return ngidz;
      case control::ControllerKind::kPpFfidz: return ffidz;
      case control::ControllerKind::kPpTraj: return traj;
    }
    return pp;
  }
};

// Validates `base` (its kind is ignored) once per law; the error says what is wrong.
inline core::Result<Tuning> make_tuning(control::ControllerConfig base) {
  Tuning t;
  control::ControllerParams* slots[] = {&t.pp, &t.ngidz, &t.ffidz, &t.traj};
  for (std::size_t i = 0; i < 4; ++i) {
    base.kind = control::kAllControllerKinds[i];
    auto p = control::ControllerParams::make(base);
    if (!p && base.kind == control::ControllerKind::kPpTraj) {
      t.traj_available = false;
      t.traj = t.pp;  // never run: selecting pp-traj is refused while it is unavailable
      continue;
    }
    if (!p) return p.error();
    *slots[i] = *p;
  }
  return t;
}

// `config` with what pp-traj takes from the loop's rules: its back-off legs kept within the loop's
// setpoint range (control/sliding_approach.hpp: a position the loop accepts as a target is one it
// may pass through), and the in-position window its hunting fallback judges its stops against.
// Every tuning the appliance gives the loop goes through here (the first and each replacement).
inline control::ControllerConfig with_loop_limits(control::ControllerConfig config, const RuntimeConfig& rules) {
  config.trajectory.travel_min_v = rules.setpoint_min_mm / rules.mm_per_volt;
  config.trajectory.travel_max_v = rules.setpoint_max_mm / rules.mm_per_volt;
  config.trajectory.in_position_window_v = rules.in_position_window_mm / rules.mm_per_volt;
  return config;
}

}  // namespace epa::runtime
