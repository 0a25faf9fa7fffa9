#pragma once
// Timing statistics of the scan cycle: wake-up latency (how late the thread woke after its
// deadline), period jitter (|actual period - Ts|) and compute time, each as a histogram with
// 1 us bins (no allocation per cycle; percentiles are read off the bins), plus overruns.
#include <array>
#include <cstdint>

namespace epa::runtime {

class LatencyHistogram {
 public:
  static constexpr std::size_t kBins = 5000;  // 1 us each: 0 .. 5 ms; beyond goes to the last bin

  void add(std::int64_t ns) noexcept {
    const std::int64_t us = ns < 0 ? 0 : ns / 1000;
    bins_[static_cast<std::size_t>(us) < kBins ? static_cast<std::size_t>(us) : kBins - 1]++;
    ++count_;
    if (ns > max_ns_) max_ns_ = ns;
  }
  // The bin (in us, upper edge) below which `fraction` of the samples lie; 0 with no samples.
  double percentile_us(double fraction) const noexcept;
  double max_us() const noexcept { return static_cast<double>(max_ns_) / 1000.0; }
  std::uint64_t count() const noexcept { return count_; }
  void reset() noexcept { *this = LatencyHistogram{}; }

 private:
  std::array<std::uint32_t, kBins> bins_{};
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
};

struct LoopStatsView {
  double wake_p50_us = 0, wake_p99_us = 0, wake_max_us = 0;
  double jitter_p50_us = 0, jitter_p99_us = 0, jitter_max_us = 0;
  double compute_p50_us = 0, compute_p99_us = 0, compute_max_us = 0;
  std::uint64_t cycles = 0, overruns = 0;
};

struct LoopStats {
  LatencyHistogram wake, jitter, compute;
  std::uint64_t overruns = 0;

  LoopStatsView view() const noexcept;
};

}  // namespace epa::runtime
