#pragma once
// A recorded run file in the run history: where it is, which controller and tuning set drove it,
// the step it made and its metrics (absent when never reached).
#include <cstdint>
#include <optional>
#include <string>

namespace epa::store {

struct RunRecord {
  std::int64_t id = 0;
  std::string path;
  std::int64_t recorded_ms = 0;
  std::string controller;                    // pp, pp-ngidz, pp-ffidz, pp-traj, open-loop
  std::optional<std::int64_t> tuning_set_id;
  std::int64_t samples = 0;
  double Ts = 0.005;
  std::optional<double> from_mm, to_mm;
  std::optional<double> rise_s, settling_s, ess_mm, overshoot_pct;
};

}  // namespace epa::store
