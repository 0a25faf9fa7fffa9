#include "app/run_history.hpp"

#include <chrono>

#include "core/audit.hpp"
#include "core/step_metrics.hpp"

namespace epa::app {

store::RunRecord to_run_record(const std::string& path, const core::Run& run) {
  store::RunRecord r;
  r.path = path;
  r.recorded_ms = core::unix_time_ms();
  r.controller = run.meta("controller");
  r.samples = static_cast<std::int64_t>(run.size());
  r.Ts = run.Ts;
  if (run.size() == 0 || run.r_mm.size() != run.size()) return r;  // no reference: no step to measure
  r.from_mm = run.y_mm.front();
  r.to_mm = run.r_mm.back();
  core::StepMetricsOptions options;
  options.Ts = run.Ts;
  const auto m = core::step_metrics(run.y_mm, run.r_mm.back(), options);
  r.rise_s = m.rise_s;
  r.settling_s = m.settling_s;
  r.overshoot_pct = m.overshoot_pct;
  r.ess_mm = m.ess_mm;
  return r;
}

}  // namespace epa::app
