#pragma once
// CLOCK_MONOTONIC in ns: the one clock the rig's threads compare their times on (steady_clock is
// the same clock, so a test reads them too).
#include <time.h>

#include <cstdint>

namespace epa::rig {

inline std::int64_t to_ns(const timespec& t) { return std::int64_t{t.tv_sec} * 1'000'000'000 + t.tv_nsec; }
inline timespec from_ns(std::int64_t ns) {
  return {static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
}
inline std::int64_t monotonic_ns() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return to_ns(now);
}

}  // namespace epa::rig
