#include "points/write_limits.hpp"

#include "core/format.hpp"
#include "points/point_catalog.hpp"
#include "runtime/excitation_settings.hpp"

namespace epa::points {

namespace {

std::string range_text(const PointRange& r) {
  return "[" + core::format_number(r.min.value) + ", " + core::format_number(r.max.value) + "]";
}

}  // namespace

core::Result<WriteLimits> WriteLimits::from_config(const runtime::RuntimeConfig& config, const std::string& config_source) {
  WriteLimits limits;
  for (const PointDef& p : point_catalog())
    limits.ranges_[index(p.id)] = {{p.min, "the point catalog"}, {p.max, "the point catalog"}};
  const std::string at = config_source.empty() ? "" : config_source + " ";
  struct Narrowing {
    PointId id;
    double min, max;
    std::string min_key, max_key;
  };
  const Narrowing from_config[] = {
      {PointId::kSetpoint, config.setpoint_min_mm, config.setpoint_max_mm, "[limits] setpoint_min_mm", "[limits] setpoint_max_mm"},
      {PointId::kManualValve, -config.manual_valve_limit_v, config.manual_valve_limit_v, "[limits] manual_valve_limit_v",
       "[limits] manual_valve_limit_v"},
  };
  for (const auto& n : from_config) {
    PointRange& r = limits.ranges_[index(n.id)];
    const std::string point_name(name(n.id));
    if (n.min < r.min.value || n.max > r.max.value)
      return core::invalid_argument(at + n.min_key + (n.min_key == n.max_key ? "" : " / " + n.max_key) + ": [" +
                                    core::format_number(n.min) + ", " + core::format_number(n.max) + "] goes beyond what '" +
                                    point_name + "' can take " + range_text(r));
    r.min = {n.min, at + n.min_key};
    r.max = {n.max, at + n.max_key};
  }
  // An experiment must fit in the recorder's ring, which the configuration sizes.
  PointRange& duration = limits.ranges_[index(PointId::kExciteDuration)];
  const double longest = runtime::max_excitation_duration_s(config);
  if (!(longest >= duration.min.value))
    return core::invalid_argument(at + "[excite] duration_s / [recorder] buffer_s: an experiment of at most " + core::format_number(longest) +
                                  " s leaves '" + std::string(name(PointId::kExciteDuration)) + "' no value within " + range_text(duration));
  if (longest < duration.max.value)
    duration.max = {longest, at + (longest > config.excitation.duration_s ? "[recorder] buffer_s (less 1 s)" : "[excite] duration_s")};
  return limits;
}

core::Status WriteLimits::narrow(PointId id, double min, double max, const std::string& source) {
  PointRange& r = ranges_[index(id)];
  PointRange next = r;
  if (min > next.min.value) next.min = {min, source};
  if (max < next.max.value) next.max = {max, source};
  if (next.min.value > next.max.value)
    return core::invalid_argument(source + ": range [" + core::format_number(min) + ", " + core::format_number(max) + "] of '" +
                                  std::string(name(id)) + "' leaves no value within " + range_text(r) + " (" + r.min.source +
                                  (r.min.source == r.max.source ? "" : ", " + r.max.source) + ")");
  r = next;
  return core::ok();
}

std::string WriteLimits::check(PointId id, double value) const {
  const PointRange& r = range(id);
  if (r.contains(value)) return {};
  const PointDef& p = point(id);
  const Bound& broken = !(value >= r.min.value) && !(value <= r.max.value) ? r.max  // NaN
                        : value < r.min.value                              ? r.min
                                                                           : r.max;
  std::string unit = p.unit.empty() ? "" : " " + std::string(p.unit);
  return std::string(p.name) + " " + core::format_number(value) + " is outside " + range_text(r) + unit + " (" +
         (&broken == &r.min ? "minimum" : "maximum") + " from " + broken.source + ")";
}

}  // namespace epa::points
