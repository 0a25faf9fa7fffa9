#pragma once
// A UTC time to the second as file names and generated names carry it, "20261124T213305Z":
// sorts by time, and has no character a file system or a tuning-set name refuses.
#include <cstdint>
#include <ctime>
#include <string>

namespace epa::core {

inline std::string utc_stamp(std::int64_t unix_time_ms) {
  const std::time_t t = static_cast<std::time_t>(unix_time_ms / 1000);
  std::tm utc{};
  gmtime_r(&t, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%SZ", &utc);
  return text;
}

}  // namespace epa::core
