#include "sim/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/format.hpp"
#include "core/units.hpp"
#include "plant/plant_adapter.hpp"

namespace epa::sim {

core::Result<StepRun> simulate_step(const core::HammersteinModel& model, const control::ControllerParams& params,
                                    const StepRunOptions& o) {
  auto plant = plant::make_hammerstein_simulator(model, {.initial_position_mm = o.initial_mm,
                                                         .noise_std_mm = o.noise_std_mm,
                                                         .seed = o.seed,
                                                         .stroke_mm = core::kStrokeMm});
  if (!plant) return plant.error();
  return simulate_step_on(**plant, model.mm_per_volt, params, o);
}

core::Result<StepRun> simulate_step_on(plant::PlantSimulator& plant, double mm_per_volt, const control::ControllerParams& params,
                                       const StepRunOptions& o, const ValveLineOptions& line) {
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s))
    return core::invalid_argument("duration must be > 0 s");
  const double target_mm = o.initial_mm + o.step_mm;
  if (!std::isfinite(target_mm) || target_mm < 0.0 || target_mm > core::kStrokeMm)
    return core::invalid_argument("target " + core::format_number(target_mm) + " mm lies outside the stroke [0, 500] mm");
  if (line.delay_samples > kMaxDelaySamples)
    return core::invalid_argument("delay of " + std::to_string(line.delay_samples) + " samples: at most " + std::to_string(kMaxDelaySamples));
  if (!(line.lag_s >= 0.0) || !std::isfinite(line.lag_s)) return core::invalid_argument("valve lag must be >= 0 s");
  const double Ts = plant.sample_period_s();
  ValveLine valve_line(line, Ts);

  const auto n = static_cast<std::size_t>(std::llround(o.duration_s / Ts));
  StepRun result;
  core::Run& run = result.run;
  run.Ts = Ts;
  run.set_meta("controller", std::string(control::to_string(params.kind())));
  run.set_meta("source", "sim");
  run.set_meta("plant", std::string(plant.kind()));
  run.set_meta("step_mm", core::format_number(o.step_mm));
  run.set_meta("initial_mm", core::format_number(o.initial_mm));
  run.set_meta("noise_std_mm", core::format_number(o.noise_std_mm));
  run.set_meta("seed", std::to_string(o.seed));
  if (line.delay_samples > 0) run.set_meta("delay_samples", std::to_string(line.delay_samples));
  if (line.lag_s > 0.0) run.set_meta("valve_lag_s", core::format_number(line.lag_s));
  for (auto* column : {&run.t_s, &run.r_mm, &run.y_mm, &run.u_V, &run.uc_V}) column->reserve(n);

  const double r_v = target_mm / mm_per_volt;
  control::ControllerState state;
  for (std::size_t k = 0; k < n; ++k) {
    const double y_v = plant.measured_v();
    const control::ControllerOutput out = control::controller_step(params, state, r_v, y_v);
    result.faults += out.fault ? 1 : 0;
    run.t_s.push_back(static_cast<double>(k) * Ts);
    run.r_mm.push_back(target_mm);
    run.y_mm.push_back(y_v * mm_per_volt);
    run.u_V.push_back(out.valve_v);
    run.uc_V.push_back(out.controller_v);
    plant.step(valve_line.pass(out.valve_v));
  }
  result.metrics = core::step_metrics(run.y_mm, target_mm, {.Ts = Ts});
  result.valve_sign_changes = count_sign_changes(run.u_V);
  return result;
}

std::size_t valve_sign_changes_in_last(const StepRun& r, double seconds) {
  const auto& u = r.run.u_V;
  const auto n = std::min(u.size(), static_cast<std::size_t>(std::llround(seconds / r.run.Ts)));
  return count_sign_changes(std::span<const double>(u).subspan(u.size() - n));
}

std::size_t count_sign_changes(std::span<const double> values) {
  std::size_t changes = 0;
  int last_sign = 0;
  for (double v : values) {
    const int sign = (v > 0.0) - (v < 0.0);
    if (sign == 0) continue;
    if (last_sign != 0 && sign != last_sign) ++changes;
    last_sign = sign;
  }
  return changes;
}

}  // namespace epa::sim
