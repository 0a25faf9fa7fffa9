#pragma once
// The load generators' latency bookkeeping (bench/modbus_load, bench/modbus_tls_load): each client
// thread counts its requests in its own histogram (1 us bins up to 100 ms, then one overflow bin;
// the exact maximum kept aside), merged at the end; percentiles are the upper edge of their bin,
// as the scan cycle's own statistics report them.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace epa::bench {

inline constexpr std::size_t kLatencyBins = 100'000;  // 1 us each: 0 .. 100 ms; one more bin for everything beyond

// One client thread's requests.
struct LatencyTally {
  std::vector<std::uint32_t> histogram = std::vector<std::uint32_t>(kLatencyBins + 1, 0);
  std::uint64_t requests = 0;
  std::uint64_t errors = 0;
  std::int64_t max_ns = 0;
  bool connected = false;

  void record(std::chrono::steady_clock::time_point start, std::chrono::steady_clock::time_point end) {
    const std::int64_t ns = std::chrono::duration_cast<std::chrono::nanoseconds>(end - start).count();
    ++histogram[std::min(static_cast<std::size_t>(ns / 1000), kLatencyBins)];
    ++requests;
    max_ns = std::max(max_ns, ns);
  }
};

// Every thread's tally together.
struct LatencySummary {
  std::vector<std::uint64_t> histogram = std::vector<std::uint64_t>(kLatencyBins + 1, 0);
  std::uint64_t requests = 0, errors = 0;
  std::int64_t max_ns = 0;
  int connected = 0;

  explicit LatencySummary(const std::vector<LatencyTally>& tallies) {
    for (const auto& t : tallies) {
      for (std::size_t i = 0; i <= kLatencyBins; ++i) histogram[i] += t.histogram[i];
      requests += t.requests;
      errors += t.errors;
      max_ns = std::max(max_ns, t.max_ns);
      connected += t.connected ? 1 : 0;
    }
  }
  double max_us() const { return requests ? static_cast<double>(max_ns) / 1000.0 : std::nan(""); }
  // Upper edge (us) of the bin holding the p-quantile; the overflow bin reports the exact maximum.
  double percentile_us(double p) const {
    if (requests == 0) return std::nan("");
    const auto want = static_cast<std::uint64_t>(std::ceil(p * static_cast<double>(requests)));
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kLatencyBins; ++i) {
      seen += histogram[i];
      if (seen >= std::max<std::uint64_t>(want, 1)) return std::min(static_cast<double>(i + 1), max_us());
    }
    return max_us();
  }
};

// A number for the JSON line; null when it is not finite.
inline std::string json_number(double v, const char* format = "%.1f") {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

}  // namespace epa::bench
