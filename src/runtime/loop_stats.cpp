#include "runtime/loop_stats.hpp"

namespace epa::runtime {

double LatencyHistogram::percentile_us(double fraction) const noexcept {
  if (count_ == 0) return 0.0;
  const auto wanted = static_cast<std::uint64_t>(fraction * static_cast<double>(count_) + 0.5);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBins; ++i) {
    seen += bins_[i];
    if (seen >= wanted && seen > 0) return static_cast<double>(i + 1);
  }
  return max_us();
}

LoopStatsView LoopStats::view() const noexcept {
  LoopStatsView v;
  v.wake_p50_us = wake.percentile_us(0.50);
  v.wake_p99_us = wake.percentile_us(0.99);
  v.wake_max_us = wake.max_us();
  v.jitter_p50_us = jitter.percentile_us(0.50);
  v.jitter_p99_us = jitter.percentile_us(0.99);
  v.jitter_max_us = jitter.max_us();
  v.compute_p50_us = compute.percentile_us(0.50);
  v.compute_p99_us = compute.percentile_us(0.99);
  v.compute_max_us = compute.max_us();
  v.cycles = compute.count();
  v.overruns = overruns;
  return v;
}

}  // namespace epa::runtime
