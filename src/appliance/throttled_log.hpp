#pragma once
// A log line of a kind a client can repeat at request speed (moves, refusals, the recorder's
// lines), through the throttle: the held-back ones are counted in the next summary.
#include <spdlog/spdlog.h>

#include <string>

#include "core/log_throttle.hpp"

namespace epa::appliance {

inline void log_throttled(core::LogThrottle& throttle, const char* kind, spdlog::level::level_enum level, const std::string& line) {
  std::string summary;
  const bool admitted = throttle.admit(kind, summary);
  if (!summary.empty()) spdlog::log(level, "{}", summary);
  if (admitted) spdlog::log(level, "{}", line);
}

}  // namespace epa::appliance
