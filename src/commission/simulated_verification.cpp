#include "commission/simulated_verification.hpp"

#include <cstdio>

#include "sim/closed_loop.hpp"
#include "sim/model_perturbation.hpp"

namespace epa::commission {

namespace {

struct Variant {
  std::string name;
  core::HammersteinModel model;
};

std::vector<Variant> variants(const core::HammersteinModel& m, const CommissionSpec& spec) {
  char buf[64];
  std::vector<Variant> out = {{"identified", m}};
  if (spec.robust_gain > 0.0)
    for (double f : {1.0 - spec.robust_gain, 1.0 + spec.robust_gain}) {
      Variant v{{}, sim::perturbed(m, {.gain_factor = f})};
      std::snprintf(buf, sizeof buf, "gain x%.2f", f);
      v.name = buf;
      out.push_back(std::move(v));
    }
  if (spec.robust_breakpoint_v > 0.0)
    for (double d : {spec.robust_breakpoint_v, -spec.robust_breakpoint_v}) {
      Variant v{{}, sim::perturbed(m, {.dead_band_widening_v = d})};
      std::snprintf(buf, sizeof buf, "dead band %+.2f V each side", d);
      v.name = buf;
      out.push_back(std::move(v));
    }
  return out;
}

}  // namespace

SimulatedVerification verify_in_simulation(const core::HammersteinModel& model, const control::ControllerParams& params,
                                           const CommissionSpec& spec, double start_mm) {
  SimulatedVerification result;
  result.passed = true;
  for (auto& v : variants(model, spec)) {
    const MoveLimits& limits = result.cases.empty() ? spec.limits : spec.robust_limits;  // the identified model first
    SimulatedCase c{v.name, {}, {}, true};
    double from = start_mm;
    for (double to : spec.moves_mm) {
      auto run = sim::simulate_step(v.model, params, {.step_mm = to - from, .initial_mm = from, .duration_s = spec.move_hold_s});
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
