#include "runtime/runtime_config.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/format.hpp"

namespace epa::runtime {

core::Status validate(const RuntimeConfig& c) {
  const struct { const char* name; double value; bool positive; } checks[] = {
      {"period_s", c.period_s, true},           {"mm_per_volt", c.mm_per_volt, true},
      {"sensor_gain", c.sensor_gain, true},     {"sensor_offset_v", c.sensor_offset_v, false},
      {"manual_valve_limit_v", c.manual_valve_limit_v, true},
      {"following_error_mm", c.following_error_mm, true},
      {"move_window_s", c.move_window_s, true}, {"record_buffer_s", c.record_buffer_s, true},
      {"in_position_window_mm", c.in_position_window_mm, true}, {"in_position_time_s", c.in_position_time_s, false},
      {"standstill_time_s", c.standstill_time_s, true},
      {"halt_decel_mm_s2", c.halt_decel_mm_s2, true}, {"jog_speed_mm_s", c.jog_speed_mm_s, true},
      {"jog_accel_mm_s2", c.jog_accel_mm_s2, true}, {"jog_keepalive_s", c.jog_keepalive_s, false},
  };
  for (const auto& ch : checks) {
    if (!std::isfinite(ch.value)) return core::invalid_argument(std::string(ch.name) + " must be a finite number");
    if (ch.positive && !(ch.value > 0.0)) return core::invalid_argument(std::string(ch.name) + " must be > 0, got " + core::format_number(ch.value));
  }
  if (c.period_s < 0.0002 || c.period_s > 1.0) return core::invalid_argument("period_s must be within [0.0002, 1] s, got " + core::format_number(c.period_s));
  // Buffers sized from a duration over the period: bounded, so a typo cannot take the memory.
  constexpr double kMaxBufferSamples = 1e6;
  if (c.record_buffer_s / c.period_s > kMaxBufferSamples)
    return core::invalid_argument("record_buffer_s / period_s is " + core::format_number(c.record_buffer_s / c.period_s) +
                                  " samples, more than the recorder keeps (" + core::format_number(kMaxBufferSamples) + ")");
  if ((c.excitation.duration_s + kExcitationRecorderSlackS) / c.period_s > kMaxBufferSamples)
    return core::invalid_argument("[excite] duration_s / period_s is " + core::format_number(c.excitation.duration_s / c.period_s) +
                                  " samples, more than the recorder keeps (" + core::format_number(kMaxBufferSamples) + ")");
  if (c.move_window_s / c.period_s > kMaxBufferSamples)
    return core::invalid_argument("move_window_s / period_s is " + core::format_number(c.move_window_s / c.period_s) +
                                  " samples, more than a move is measured over (" + core::format_number(kMaxBufferSamples) + ")");
  if (!(c.sensor_min_v < c.sensor_max_v)) return core::invalid_argument("sensor_min_v must be below sensor_max_v");
  if (!(c.soft_min_mm < c.soft_max_mm)) return core::invalid_argument("soft_min_mm must be below soft_max_mm");
  if (!(c.setpoint_min_mm <= c.setpoint_max_mm)) return core::invalid_argument("setpoint_min_mm must not exceed setpoint_max_mm");
  if (c.setpoint_min_mm < c.soft_min_mm || c.setpoint_max_mm > c.soft_max_mm)
    return core::invalid_argument("the setpoint range [" + core::format_number(c.setpoint_min_mm) + ", " + core::format_number(c.setpoint_max_mm) +
                                  "] mm must lie inside the soft limits [" + core::format_number(c.soft_min_mm) + ", " + core::format_number(c.soft_max_mm) + "] mm");
  if (!std::isfinite(c.safe_valve_v) || std::abs(c.safe_valve_v) > 10.0)  // the valve accepts +-10 V
    return core::invalid_argument("safe_valve_v must be a valve command within +-10 V, got " + core::format_number(c.safe_valve_v));
  if (c.in_position_time_s < 0.0 || c.jog_keepalive_s < 0.0)
    return core::invalid_argument("[motion] in_position_time_s and jog_keepalive_s must be >= 0");
  if (!(c.following_error_time_s >= 0.0)) return core::invalid_argument("following_error_time_s must be >= 0 (0: off)");
  if (!(c.heartbeat_timeout_s >= 0.0)) return core::invalid_argument("heartbeat_timeout_s must be >= 0 (0: off)");
  if (!(c.sensor_frozen_time_s >= 0.0)) return core::invalid_argument("sensor_frozen_time_s must be >= 0 (0: off)");
  if (!(c.sensor_frozen_drive_v > 0.0)) return core::invalid_argument("sensor_frozen_drive_v must be > 0 V");
  if (c.max_consecutive_io_errors < 1) return core::invalid_argument("max_consecutive_io_errors must be >= 1");
  if (c.max_consecutive_overruns < 1) return core::invalid_argument("max_consecutive_overruns must be >= 1");
  if (c.start_mode != Mode::kStop && c.start_mode != Mode::kRun)
    return core::invalid_argument("start mode must be stop or run (manual and excite are entered by command)");
  if (c.start_setpoint_mm < c.setpoint_min_mm || c.start_setpoint_mm > c.setpoint_max_mm)
    return core::invalid_argument("start setpoint " + core::format_number(c.start_setpoint_mm) + " mm lies outside the setpoint range [" +
                                  core::format_number(c.setpoint_min_mm) + ", " + core::format_number(c.setpoint_max_mm) + "] mm");
  if (c.move_window_s > c.record_buffer_s) return core::invalid_argument("move_window_s must not exceed record_buffer_s");
  if (const char* problem = excitation_problem(c.excitation, c)) {
    const auto& e = c.excitation;
    return core::invalid_argument(std::string("[excite] ") + problem + " (amplitude_min_v " + core::format_number(e.amplitude_min_v) +
                                  ", amplitude_max_v " + core::format_number(e.amplitude_max_v) + ", duration_s " +
                                  core::format_number(e.duration_s) + ", guard_mm " + core::format_number(e.guard_mm) +
                                  "; soft limits [" + core::format_number(c.soft_min_mm) + ", " + core::format_number(c.soft_max_mm) + "] mm)");
  }
  return core::ok();
}

std::size_t record_capacity_samples(const RuntimeConfig& c) {
  const auto buffer = static_cast<std::size_t>(c.record_buffer_s / c.period_s);
  const auto excitation = static_cast<std::size_t>(std::ceil((c.excitation.duration_s + kExcitationRecorderSlackS) / c.period_s));
  return std::max(buffer, excitation);
}

}  // namespace epa::runtime
