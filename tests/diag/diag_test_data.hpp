#pragma once
// Test data for the diagnosis: runs from the paper's model, slightly perturbed, with an effect
// hidden in the simulator (or none, or one outside the library), seeded sensor noise, closed-loop
// (the paper's FF-IDZ controller on a sequence of setpoints) and open-loop (the excitation of
// `epa excite`). Shared by the diag tests, the self-check and the benchmark.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/paper_reference.hpp"
#include "core/random.hpp"
#include "core/run.hpp"
#include "ident/excitation.hpp"
#include "plant/augmented_plant.hpp"

namespace epa::testing {

// What the simulator hides. `periodic_mm` > 0 adds an oscillation of that amplitude to the
// measurement: a 4 Hz disturbance no effect in the library describes.
// `fractional_delay_samples` > 0 delays the command by that many samples, interpolated between
// the two whole delays around it (the library's delay is whole samples).
// `slew_V_per_s` > 0 moves the spool toward the command by at most that much, a hard clip (the
// library's speed limit has a rounded knee).
// `sagging_supply_bar` > 0: the supply falls from 6 bar toward that pressure with a 6-s time
// constant from each run's start (a receiver the compressor refills only between runs), and the
// valve's flow goes with the square root of supply less 1 bar of exhaust (the library's drifting
// gain is linear in time and knows no pressure); applied to the command beyond the break points.
struct Hidden {
  plant::EffectSet effects;
  double periodic_mm = 0.0;
  double fractional_delay_samples = 0.0;
  double slew_V_per_s = 0.0;
  double sagging_supply_bar = 0.0;
};

// The flow's share at time t of a supply sagging toward `to_bar` (Hidden::sagging_supply_bar).
inline double sagging_supply_flow_ratio(double to_bar, double t_s) {
  const double supply_bar = to_bar + (6.0 - to_bar) * std::exp(-t_s / 6.0);
  return std::sqrt((supply_bar - 1.0) / (6.0 - 1.0));
}

// The paper's model as a rig might differ from it within what identification gives back: B
// scaled by up to +-3 % (the steady gain), break points moved by up to +-0.02 V. The diagnosis
// re-fits these first; its tolerances are calibrated on such models. perturbation 0: the paper's.
inline core::HammersteinModel perturbed_model(std::uint64_t seed, double perturbation = 1.0) {
  core::Random rng(seed * 7919 + 3);
  auto m = core::paper::model();
  const double gain = 1.0 + perturbation * 0.03 * (2.0 * rng.uniform() - 1.0);
  m.B = m.B * gain;
  m.dead_zone.b_r += perturbation * 0.02 * (2.0 * rng.uniform() - 1.0);
  m.dead_zone.b_l += perturbation * 0.02 * (2.0 * rng.uniform() - 1.0);
  return m;
}

struct RunSpec {
  bool closed_loop = true;
  double duration_s = 10.0;
  double noise_std_mm = 0.1;
  std::uint64_t seed = 1;
};

inline core::Run make_run(const core::HammersteinModel& truth, const Hidden& hidden, const RunSpec& spec) {
  auto plant = plant::AugmentedPlant::make(truth, hidden.effects,
                                           {.initial_position_mm = 250.0, .noise_std_mm = spec.noise_std_mm, .seed = spec.seed});
  core::Run run;
  run.Ts = truth.Ts;
  run.set_meta("source", "sim");
  run.set_meta("controller", spec.closed_loop ? "pp-ffidz" : "open-loop");
  run.set_meta("hidden", hidden.effects.describe() + (hidden.periodic_mm > 0 ? " + periodic" : ""));
  const auto n = static_cast<std::size_t>(std::llround(spec.duration_s / truth.Ts));
  core::Random rng(spec.seed * 31 + 17);
  auto params = control::ControllerParams::make(control::paper_controller_config(control::ControllerKind::kPpFfidz));
  control::ControllerState state;
  ident::ExcitationOptions eo;
  eo.Ts = truth.Ts, eo.duration_s = spec.duration_s, eo.seed = spec.seed;
  auto gen = ident::ExcitationGenerator::make(eo);
  double setpoint_mm = 250.0;
  std::size_t next_setpoint = 0;
  double spool_V = 0.0;  // slew_V_per_s's spool
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * truth.Ts;
    double y_mm = plant->measured_mm();
    if (hidden.periodic_mm > 0) y_mm += hidden.periodic_mm * std::sin(2.0 * std::numbers::pi * 4.0 * t);
    double u = 0.0;
    if (spec.closed_loop) {
      if (k == next_setpoint) {  // every 1-2.5 s a new setpoint, small and large moves both ways
        const double size = rng.uniform() < 0.4 ? 5.0 + 15.0 * rng.uniform() : 40.0 + 120.0 * rng.uniform();
        const double dir = setpoint_mm > 380 ? -1.0 : setpoint_mm < 120 ? 1.0 : (rng.uniform() < 0.5 ? -1.0 : 1.0);
        setpoint_mm += dir * size;
        next_setpoint = k + static_cast<std::size_t>((1.0 + 1.5 * rng.uniform()) / truth.Ts);
      }
      u = control::controller_step(*params, state, setpoint_mm / truth.mm_per_volt, y_mm / truth.mm_per_volt).valve_v;
      run.r_mm.push_back(setpoint_mm);
    } else {
      u = gen->next(y_mm);
    }
    run.t_s.push_back(t);
    run.y_mm.push_back(y_mm);
    run.u_V.push_back(u);
    if (hidden.fractional_delay_samples > 0.0) {
      const double d = hidden.fractional_delay_samples, whole = std::floor(d);
      auto past = [&](double samples) {
        const auto i = static_cast<std::size_t>(samples);
        return i <= k ? run.u_V[k - i] : 0.0;
      };
      u = (1.0 - (d - whole)) * past(whole) + (d - whole) * past(whole + 1.0);
    }
    if (hidden.sagging_supply_bar > 0.0) {  // the drive beyond each break point scaled with the flow
      const double ratio = sagging_supply_flow_ratio(hidden.sagging_supply_bar, t);
      if (u > truth.dead_zone.b_r) u = truth.dead_zone.b_r + ratio * (u - truth.dead_zone.b_r);
      if (u < truth.dead_zone.b_l) u = truth.dead_zone.b_l + ratio * (u - truth.dead_zone.b_l);
    }
    if (hidden.slew_V_per_s > 0.0) {
      const double most_V = hidden.slew_V_per_s * truth.Ts;
      spool_V += std::clamp(u - spool_V, -most_V, most_V);
      u = spool_V;
    }
    plant->step(u);
  }
  return run;
}

// A case: `train` and `heldout` runs, alternating closed- and open-loop, each with its own seed.
struct CaseData {
  std::vector<core::Run> train, heldout;
};
inline CaseData make_case(const Hidden& hidden, std::uint64_t seed, std::size_t train_runs = 4, std::size_t heldout_runs = 2,
                          double duration_s = 10.0, double perturbation = 1.0, double noise_std_mm = 0.1) {
  const auto truth = perturbed_model(seed, perturbation);
  CaseData c;
  for (std::size_t i = 0; i < train_runs + heldout_runs; ++i) {
    const RunSpec spec{.closed_loop = i % 2 == 0, .duration_s = duration_s, .noise_std_mm = noise_std_mm,
                       .seed = seed * 1000 + i + 1};
    (i < train_runs ? c.train : c.heldout).push_back(make_run(truth, hidden, spec));
  }
  return c;
}

// The eight hidden effects of the self-check, at sizes a rig shows.
inline plant::EffectSet typical_effect(plant::EffectKind kind) {
  using K = plant::EffectKind;
  plant::EffectSet e;
  switch (kind) {
    case K::kGainChange: e.set(kind, {0.75}); break;
    case K::kDeadzoneShift: e.set(kind, {0.3, -0.25}); break;
    case K::kInputDelay: e.set(kind, {3}); break;
    case K::kValveLag: e.set(kind, {0.015}); break;
    case K::kStaticFriction: e.set(kind, {0.6, 0.3}); break;
    case K::kFlowSaturation: e.set(kind, {150.0}); break;
    case K::kPositionDependentGain: e.set(kind, {0.1}); break;
    case K::kSensorQuantization: e.set(kind, {1.5}); break;
  }
  return e;
}

inline std::vector<const core::Run*> pointers(const std::vector<core::Run>& runs) {
  std::vector<const core::Run*> p;
  for (const auto& r : runs) p.push_back(&r);
  return p;
}

}  // namespace epa::testing
