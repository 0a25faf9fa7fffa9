// The one rule for "the same sample time" (a model's, a run's, the loop's period): equal to a
// part in 1e9, whatever the scale; a real difference, however small against a second, is not.
#include "core/units.hpp"

#include <gtest/gtest.h>

namespace {

TEST(SampleTime, TheSameToAPartInABillionAndNoCloserDifferenceIsIgnored) {
  using epa::core::same_sample_time;
  EXPECT_TRUE(same_sample_time(0.005, 0.005));
  EXPECT_TRUE(same_sample_time(0.005, 0.005 * (1.0 + 4e-10)));  // the same decimal text read twice
  EXPECT_TRUE(same_sample_time(0.001 * 5, 0.005));
  EXPECT_FALSE(same_sample_time(0.005, 0.005 * (1.0 + 2e-9)));
  EXPECT_FALSE(same_sample_time(0.005, 0.004));
  EXPECT_FALSE(same_sample_time(0.005, 0.0));
  EXPECT_TRUE(same_sample_time(1e-6, 1e-6 * (1.0 + 4e-10)));  // relative: a fast loop is judged alike
  EXPECT_FALSE(same_sample_time(1e-6, 1.001e-6));
}

}  // namespace
