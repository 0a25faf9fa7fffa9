#include "core/random.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace epa::core {
namespace {

constexpr int kDraws = 100'000;
// Sampling tolerances for kDraws draws: the standard error of a mean of N(0,1) draws is
// 1/sqrt(1e5) = 0.0032 and of their standard deviation about 0.0022, so 0.02 is more than six
// standard errors (the seeds are fixed, so the test is deterministic anyway).
constexpr double kNormalMomentTol = 0.02;
// Uniform(0,1): standard error of the mean 0.289/sqrt(1e5) = 0.0009.
constexpr double kUniformMeanTol = 0.005;
// Fraction of N(0,1) within one standard deviation, 0.6827; standard error sqrt(p(1-p)/N) = 0.0015.
constexpr double kFractionTol = 0.01;

std::vector<std::uint64_t> draw_u64(Random& r, int n) {
  std::vector<std::uint64_t> v;
  for (int i = 0; i < n; ++i) v.push_back(r.next_u64());
  return v;
}

TEST(Random, SameSeedGivesTheSameSequence) {
  Random a(12345), b(12345);
  EXPECT_EQ(draw_u64(a, 1000), draw_u64(b, 1000));
  Random c(7), d(7);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(c.normal(), d.normal()) << "draw " << i;
}

TEST(Random, DifferentSeedsGiveDifferentSequences) {
  Random a(1), b(2);
  const auto va = draw_u64(a, 100), vb = draw_u64(b, 100);
  int equal = 0;
  for (std::size_t i = 0; i < va.size(); ++i) equal += va[i] == vb[i];
  EXPECT_EQ(equal, 0);
}

TEST(Random, MatchesThePublishedSplitMix64Sequence) {
  // Reference outputs of Vigna's splitmix64 (state += golden gamma, then the two xor-shift-
  // multiply rounds) for seed 0; the sequence must not depend on the standard library.
  Random r(0);
  EXPECT_EQ(r.next_u64(), 0xE220A8397B1DCDAFull);
  EXPECT_EQ(r.next_u64(), 0x6E789E6AA1B965F4ull);
  EXPECT_EQ(r.next_u64(), 0x06C45D188009454Full);
}

TEST(Random, DefaultSeedIsOne) {
  Random a, b(1);
  EXPECT_EQ(draw_u64(a, 10), draw_u64(b, 10));
}

TEST(Random, UniformIsStrictlyInsideZeroOne) {
  Random r(99);
  double sum = 0.0, lo = 1.0, hi = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    const double u = r.uniform();
    ASSERT_GT(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  EXPECT_NEAR(sum / kDraws, 0.5, kUniformMeanTol);
  EXPECT_LT(lo, 1e-3);  // the whole interval is covered
  EXPECT_GT(hi, 1.0 - 1e-3);
}

TEST(Random, NormalHasZeroMeanAndUnitStandardDeviation) {
  Random r(2024);
  double sum = 0.0, sum_sq = 0.0;
  int within_one = 0;
  for (int i = 0; i < kDraws; ++i) {
    const double x = r.normal();
    ASSERT_TRUE(std::isfinite(x));
    sum += x;
    sum_sq += x * x;
    within_one += std::abs(x) < 1.0;
  }
  const double mean = sum / kDraws;
  const double sd = std::sqrt(sum_sq / kDraws - mean * mean);
  EXPECT_NEAR(mean, 0.0, kNormalMomentTol);
  EXPECT_NEAR(sd, 1.0, kNormalMomentTol);
  EXPECT_NEAR(static_cast<double>(within_one) / kDraws, 0.6827, kFractionTol);
}

TEST(Random, CopyContinuesTheSameStream) {
  Random original(555);
  for (int i = 0; i < 17; ++i) original.next_u64();
  Random copy = original;
  for (int i = 0; i < 200; ++i) {
    ASSERT_EQ(copy.next_u64(), original.next_u64()) << "draw " << i;
    ASSERT_EQ(copy.normal(), original.normal()) << "draw " << i;
  }
}

TEST(Random, CopyIsIndependentOfTheOriginalAfterwards) {
  Random original(555);
  Random copy = original;
  const std::uint64_t first = copy.next_u64();
  original.next_u64();
  original.next_u64();  // advancing the original does not move the copy
  Random fresh(555);
  fresh.next_u64();
  EXPECT_EQ(copy.next_u64(), fresh.next_u64());
  EXPECT_NE(first, copy.next_u64());
}

}  // namespace
}  // namespace epa::core
