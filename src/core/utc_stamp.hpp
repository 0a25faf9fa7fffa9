#pragma once
// UTC times as text. utc_stamp: to the second as file names and generated names carry it,
// "20261124T213305Z": sorts by time, and has no character a file system or a tuning-set name refuses.
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <string>

namespace epa::core {

inline std::tm utc_time(std::int64_t unix_time_ms) {
  const std::time_t t = static_cast<std::time_t>(unix_time_ms / 1000);
  std::tm utc{};
  gmtime_r(&t, &utc);
  return utc;
}

inline std::string utc_stamp(std::int64_t unix_time_ms) {
  const std::tm utc = utc_time(unix_time_ms);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%SZ", &utc);
  return text;
}

// ISO 8601 in UTC to the millisecond, as the JSON API and the command line show times:
// "YYYY-MM-DDThh:mm:ss.mmmZ".
inline std::string iso_utc(std::int64_t unix_time_ms) {
  const std::tm utc = utc_time(unix_time_ms);
  char text[40];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  char out[48];
  std::snprintf(out, sizeof out, "%s.%03dZ", text, static_cast<int>(unix_time_ms % 1000));
  return out;
}

}  // namespace epa::core
