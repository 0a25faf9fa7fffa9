#pragma once
// One set of limits for every write, whichever interface it comes through: each writable point's
// range from the catalog, narrowed by the configuration ([limits] setpoint_min_mm/max_mm,
// manual_valve_limit_v; the recorder's ring for excite_duration_s) and by the register map's
// min/max columns. Each bound remembers where it
// came from, so a refusal names the limit ("setpoint_mm 400 is outside [0, 300] mm: [limits]
// setpoint_max_mm"). Limits that leave a point no value at all are refused at start-up.
#include <array>
#include <string>

#include "core/result.hpp"
#include "points/point_id.hpp"
#include "runtime/runtime_config.hpp"

namespace epa::points {

struct Bound {
  double value = 0;
  std::string source;  // "the point catalog", "[limits] setpoint_max_mm", "registers/epa.csv line 2"
};

struct PointRange {
  Bound min, max;
  bool contains(double v) const { return v >= min.value && v <= max.value; }  // false for NaN
};

class WriteLimits {
 public:
  // The catalog's ranges narrowed by `config`. Refused when the configuration asks for values the
  // point itself cannot take (e.g. setpoint_max_mm beyond the stroke the catalog allows).
  static core::Result<WriteLimits> from_config(const runtime::RuntimeConfig& config, const std::string& config_source);

  // Narrows one point's range (a register map's row); refused when nothing would be left.
  core::Status narrow(PointId id, double min, double max, const std::string& source);

  const PointRange& range(PointId id) const { return ranges_[index(id)]; }

  // "" when `value` is within the point's range, else the sentence that names the limit.
  std::string check(PointId id, double value) const;

 private:
  std::array<PointRange, kPointCount> ranges_;
};

}  // namespace epa::points
