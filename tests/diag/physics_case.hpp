#pragma once
// Self-check data from the physics plant: the pneumatic cylinder (plant::PneumaticPlant) with a
// valve- or sensor-side effect hidden around it, closed-loop (FF-IDZ on random setpoints) and
// open-loop (the excitation of `epa excite`) runs with seeded noise, and the nominal model a
// commissioning engineer would have for it: dead zone at the valve's overlap and a 3rd-order ARX
// model fitted by least squares on effect-free runs of the same plant.
#include <string>
#include <vector>

#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/random.hpp"
#include "core/run.hpp"
#include "ident/arx_estimator.hpp"
#include "ident/excitation.hpp"
#include "ident/ident_data.hpp"
#include "plant/augmented_plant.hpp"
#include "plant/pneumatic_plant.hpp"

namespace epa::testing {

inline core::Run make_physics_run(const plant::EffectSet& hidden, bool closed_loop, double duration_s, std::uint64_t seed) {
  constexpr double kTs = 0.005;
  plant::PneumaticOptions options;
  options.initial_position_mm = 250.0;
  options.noise_std_mm = 0.1;
  options.seed = seed;
  options.Ts = kTs;
  auto cylinder = plant::PneumaticPlant::make(plant::PneumaticParams{}, options);
  plant::WithValveAndSensorEffects<plant::PneumaticPlant> rig(std::move(*cylinder), hidden, kTs);
  core::Run run;
  run.Ts = kTs;
  run.set_meta("source", "physics");
  run.set_meta("controller", closed_loop ? "pp-ffidz" : "open-loop");
  auto params = control::ControllerParams::make(control::paper_controller_config(control::ControllerKind::kPpFfidz));
  control::ControllerState state;
  ident::ExcitationOptions eo;
  eo.Ts = kTs, eo.duration_s = duration_s, eo.seed = seed;
  auto gen = ident::ExcitationGenerator::make(eo);
  core::Random rng(seed * 131 + 7);
  double setpoint_mm = 250.0;
  std::size_t next_setpoint = 0;
  const auto n = static_cast<std::size_t>(duration_s / kTs);
  for (std::size_t k = 0; k < n; ++k) {
    const double y_mm = rig.measured_mm();
    double u = 0.0;
    if (closed_loop) {
      if (k == next_setpoint) {
        const double size = rng.uniform() < 0.4 ? 10.0 + 15.0 * rng.uniform() : 40.0 + 120.0 * rng.uniform();
        const double dir = setpoint_mm > 380 ? -1.0 : setpoint_mm < 120 ? 1.0 : (rng.uniform() < 0.5 ? -1.0 : 1.0);
        setpoint_mm += dir * size;
        next_setpoint = k + static_cast<std::size_t>((1.0 + 1.5 * rng.uniform()) / kTs);
      }
      u = control::controller_step(*params, state, setpoint_mm / 50.0, y_mm / 50.0).valve_v;
      run.r_mm.push_back(setpoint_mm);
    } else {
      u = gen->next(y_mm);
    }
    run.t_s.push_back(static_cast<double>(k) * kTs);
    run.y_mm.push_back(y_mm);
    run.u_V.push_back(u);
    rig.step(u);
  }
  return run;
}

// The nominal model of the physics plant: the valve overlap as the dead zone, ARX(3,3,1) by least
// squares on `runs` (effect-free).
inline core::HammersteinModel identify_physics_nominal(const std::vector<core::Run>& runs) {
  const core::DeadZone overlap{1.0, 1.0, 1.2, -1.7};
  std::vector<ident::Segment> segments;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    auto s = ident::split_run(runs[i], "physics-" + std::to_string(i), ident::SegmentOptions{});
    segments.insert(segments.end(), s.begin(), s.end());
  }
  auto estimate = ident::estimate_arx(ident::through_dead_zone(segments, overlap), ident::ArxOrders{3, 3, 1});
  core::HammersteinModel m;
  m.A = estimate->model.A();
  m.B = estimate->model.B();
  m.dead_zone = overlap;
  m.Ts = 0.005;
  m.mm_per_volt = 50.0;
  return m;
}

}  // namespace epa::testing
