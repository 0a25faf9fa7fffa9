#include "appliance/run_history.hpp"

#include <cmath>

#include "core/audit.hpp"
#include "core/move_metrics.hpp"
#include "core/run_file.hpp"

namespace epa::appliance {

namespace {
std::optional<double> finite(double v) { return std::isfinite(v) ? std::optional(v) : std::nullopt; }
std::optional<double> meta_number(const core::Run& run, const std::string& key) { return core::parse_number(run.meta(key)); }
}  // namespace

store::RunRecord to_run_record(const std::string& path, const core::Run& run) {
  store::RunRecord r;
  r.path = path;
  r.recorded_ms = core::unix_time_ms();
  r.controller = run.meta("controller");
  r.samples = static_cast<std::int64_t>(run.size());
  r.Ts = run.Ts;
  // A move's file says where it went and how it ended: its figures are the loop's, recomputed by
  // the same function from the same samples. Any other recording is a window, not a step.
  const auto end = core::parse_move_end(run.meta("move_end"));
  const auto from = meta_number(run, "from_mm"), target = meta_number(run, "target_mm");
  const auto ess_window = meta_number(run, "ess_window_s");
  if (run.size() == 0 || !end || !from || !target || !ess_window) return r;
  r.from_mm = *from;
  r.to_mm = *target;
  const auto m = core::move_metrics(run.y_mm, *from, *target, *end, {.Ts = run.Ts, .ess_window_s = *ess_window});
  r.rise_s = finite(m.rise_s);
  r.settling_s = finite(m.settling_s);
  r.overshoot_pct = finite(m.overshoot_pct);
  r.ess_mm = finite(m.ess_mm);
  return r;
}

}  // namespace epa::appliance
