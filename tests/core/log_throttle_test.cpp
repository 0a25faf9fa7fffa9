#include "core/log_throttle.hpp"

#include <gtest/gtest.h>

namespace epa::core {
namespace {

TEST(LogThrottle,
     AWindowLogsItsAllowanceThenCountsTheRestInTheNextWindowsFirstLine) {
  std::int64_t now_ns = 0;
  LogThrottle throttle(3, 60.0, [&] { return now_ns; });
  std::string summary;
  int logged = 0;
  for (int i = 0; i < 415; ++i) {
    logged += throttle.admit("audit", summary) ? 1 : 0;
    EXPECT_TRUE(summary.empty());
  }
  EXPECT_EQ(logged, 3);
  now_ns += 61'000'000'000;
  EXPECT_TRUE(throttle.admit("audit", summary));
  EXPECT_EQ(summary, "412 more 'audit' lines in the last 61 s (not logged: at "
                     "most 3 a window)");
}

TEST(LogThrottle, KindsAreCountedApartAndAStoppedFloodIsStillReported) {
  std::int64_t now_ns = 0;
  LogThrottle throttle(1, 60.0, [&] { return now_ns; });
  std::string summary;
  EXPECT_TRUE(throttle.admit("audit", summary));
  EXPECT_FALSE(throttle.admit("audit", summary));
  EXPECT_TRUE(
      throttle.admit("move", summary)); // another kind has its own allowance
  EXPECT_TRUE(throttle.due_summaries().empty()); // the window has not ended
  now_ns += 60'000'000'000;
  const auto due = throttle.due_summaries();
  ASSERT_EQ(due.size(), 1u);
  EXPECT_EQ(
      due.front(),
      "1 more 'audit' lines in the last 60 s (not logged: at most 1 a window)");
  EXPECT_TRUE(throttle.due_summaries().empty()); // reported once
}

} // namespace
} // namespace epa::core
