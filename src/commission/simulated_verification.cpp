#include "commission/simulated_verification.hpp"

#include <fmt/format.h>

#include "core/units.hpp"
#include "plant/plant_adapter.hpp"
#include "sim/closed_loop.hpp"
#include "sim/model_perturbation.hpp"

namespace epa::commission {

namespace {

struct Variant {
  std::string name;
  core::HammersteinModel model;
  std::optional<core::StickSlipParams> axis;  // the plant instead of `model`, when set
};

core::StickSlipParams perturbed_axis(core::StickSlipParams p, double gain_factor, double widening_v) {
  p.speed_right_mm_s_per_v *= gain_factor;
  p.speed_left_mm_s_per_v *= gain_factor;
  p.break_right_v += widening_v;
  p.break_left_v -= widening_v;
  return p;
}

std::vector<Variant> variants(const core::HammersteinModel& m, const std::optional<core::StickSlipParams>& axis,
                              const CommissionSpec& spec) {
  std::vector<Variant> out = {{"identified", m, axis}};
  if (spec.robust_gain > 0.0)
    for (double f : {1.0 - spec.robust_gain, 1.0 + spec.robust_gain}) {
      Variant v{{}, sim::perturbed(m, {.gain_factor = f}), axis ? std::optional(perturbed_axis(*axis, f, 0.0)) : std::nullopt};
      v.name = fmt::format("gain x{:.2f}", f);
      out.push_back(std::move(v));
    }
  if (spec.robust_breakpoint_v > 0.0)
    for (double d : {spec.robust_breakpoint_v, -spec.robust_breakpoint_v}) {
      Variant v{{}, sim::perturbed(m, {.dead_band_widening_v = d}), axis ? std::optional(perturbed_axis(*axis, 1.0, d)) : std::nullopt};
      v.name = fmt::format("dead band {:+.2f} V each side", d);
      out.push_back(std::move(v));
    }
  return out;
}

core::Result<sim::StepRun> simulate_move(const Variant& v, const control::ControllerParams& params, double from, double to,
                                         double duration_s) {
  const sim::StepRunOptions options{.step_mm = to - from, .initial_mm = from, .duration_s = duration_s};
  if (!v.axis) return sim::simulate_step(v.model, params, options);
  auto plant = plant::make_stick_slip_simulator(*v.axis, v.model.Ts, v.model.mm_per_volt,
                                                {.initial_position_mm = from, .stroke_mm = core::kStrokeMm});
  if (!plant) return plant.error();
  return sim::simulate_step_on(**plant, v.model.mm_per_volt, params, options);
}

}  // namespace

SimulatedVerification verify_in_simulation(const core::HammersteinModel& model, const std::optional<core::StickSlipParams>& axis,
                                           const control::ControllerParams& params, const CommissionSpec& spec, double start_mm) {
  SimulatedVerification result;
  result.passed = true;
  for (auto& v : variants(model, axis, spec)) {
    const MoveLimits& limits = result.cases.empty() ? spec.limits : spec.robust_limits;  // the identified model first
    SimulatedCase c{v.name, {}, {}, true};
    double from = start_mm;
    for (double to : spec.moves_mm) {
      auto run = simulate_move(v, params, from, to, spec.move_hold_s);
      JudgedMove j = run ? judge_move(from, to, run->metrics, limits) : JudgedMove{from, to, {}, false, run.error().message};
      if (!j.passed && c.passed) {
        c.passed = false;
        if (result.passed) result.passed = false, result.why = "simulation, " + v.name + ": " + j.why;
      }
      c.moves.push_back(std::move(j));
      c.positions_mm.push_back(run ? run->run.y_mm : std::vector<double>{});
      from = to;
    }
    result.cases.push_back(std::move(c));
  }
  return result;
}

}  // namespace epa::commission
