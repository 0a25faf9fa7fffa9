#include "runtime/excitation_settings.hpp"

#include <algorithm>
#include <cmath>

#include "runtime/runtime_config.hpp"

namespace epa::runtime {

namespace {
constexpr double kValveRangeV = 10.0;      // the proportional valve accepts +-10 V
constexpr double kMinDurationS = 1.0;      // shorter is no experiment (the ramps alone take seconds)
}  // namespace

double max_excitation_duration_s(const RuntimeConfig& config) noexcept {
  return std::max(config.record_buffer_s - kExcitationRecorderSlackS, config.excitation.duration_s);
}

const char* excitation_problem(const ExcitationSettings& s, const RuntimeConfig& config) noexcept {
  if (!(s.amplitude_max_v > 0.0 && s.amplitude_max_v <= kValveRangeV))
    return "the excitation's amplitude_max_v must lie in (0, 10] V, the valve's range";
  if (!(s.amplitude_min_v > 0.0 && s.amplitude_min_v <= s.amplitude_max_v))
    return "the excitation's amplitude_min_v must lie in (0 V, amplitude_max_v]";
  if (!(s.duration_s >= kMinDurationS && std::isfinite(s.duration_s))) return "the excitation's duration_s must be at least 1 s";
  if (!(s.duration_s <= max_excitation_duration_s(config)))
    return "the excitation's duration_s must fit in the recorder's ring (at most [recorder] buffer_s less 1 s, or the configured "
           "[excite] duration_s if that is longer), so the whole run is written";
  const double span_mm = config.soft_max_mm - config.soft_min_mm;
  if (!(s.guard_mm > 0.0 && 2.0 * s.guard_mm < span_mm))
    return "the excitation's guard_mm must lie in (0, half the span between the soft limits)";
  return nullptr;
}

bool excitation_may_start_at(double position_mm, const ExcitationSettings& s, const RuntimeConfig& config) noexcept {
  return position_mm >= config.soft_min_mm + s.guard_mm && position_mm <= config.soft_max_mm - s.guard_mm;
}

}  // namespace epa::runtime
