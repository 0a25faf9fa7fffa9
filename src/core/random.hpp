#pragma once
// A small seeded random source whose sequence is fixed by this code alone (std::normal_distribution
// differs between standard libraries), so a seeded run gives the same file on every machine.
#include <cmath>
#include <cstdint>
#include <numbers>

namespace epa::core {

class Random {
 public:
  explicit Random(std::uint64_t seed = 1) : state_(seed) {}

  // splitmix64: full-period, passes BigCrush, and trivially copyable as plant state.
  std::uint64_t next_u64() noexcept {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }

  // Uniform in (0, 1): never 0, so log() below is finite.
  double uniform() noexcept { return (static_cast<double>(next_u64() >> 11) + 0.5) * 0x1.0p-53; }

  // Standard normal by Box-Muller (one value per call: simpler state, cost is irrelevant here).
  double normal() noexcept {
    const double u1 = uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace epa::core
