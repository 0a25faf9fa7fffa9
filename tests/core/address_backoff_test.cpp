// The guess back-off keyed per connection plus per address: a guesser is slowed, the holder of the
// right secret on the same address is not refused, and a success clears only its own connection.
#include "core/address_backoff.hpp"

#include <gtest/gtest.h>

namespace epa::core {
namespace {

constexpr std::int64_t kS = 1'000'000'000;

TEST(AddressBackoff, FiveWrongOnAConnectionLockItOutDoublingUpToFiveMinutes) {
  AddressBackoff b;
  const Guesser g{"10.0.0.9", "10.0.0.9:4000", 0};
  for (int i = 1; i <= 4; ++i) EXPECT_FALSE(b.wrong(g, i).started);
  const auto l = b.wrong(g, 5);
  EXPECT_TRUE(l.started);
  EXPECT_EQ(l.backoff_ns, 10 * kS);
  EXPECT_EQ(b.refused_until(g, 6), 5 + 10 * kS);
  EXPECT_EQ(b.refused_until(g, 5 + 10 * kS), 0);
  EXPECT_EQ(b.wrong(g, 11 * kS).backoff_ns, 20 * kS);  // the next wrong one: twice as long
  std::int64_t t = 11 * kS, last = 0;
  for (int i = 0; i < 10; ++i) t += 400 * kS, last = b.wrong(g, t).backoff_ns;
  EXPECT_EQ(last, AddressBackoff::kMaxBackoffNs);
}

TEST(AddressBackoff, InAnAddressBackOffOnlyAConnectionOpenTwoSecondsWithoutAWrongGuessIsHeard) {
  AddressBackoff b;
  for (int i = 0; i < 5; ++i) b.wrong({"10.0.0.9", "10.0.0.9:" + std::to_string(5000 + i), 0}, kS);  // five reconnects
  const Guesser fresh{"10.0.0.9", "10.0.0.9:6000", kS};
  EXPECT_EQ(b.refused_until(fresh, kS + 1), 3 * kS);  // not open 2 s yet: heard from 3 s on
  EXPECT_EQ(b.refused_until(fresh, 3 * kS), 0);
  const Guesser engineer{"10.0.0.9", "10.0.0.9:6001", 0};
  EXPECT_EQ(b.refused_until(engineer, 2 * kS), 0);  // open 2 s, no wrong guess: heard
  b.right(engineer);
  EXPECT_NE(b.refused_until(fresh, kS + 1), 0);  // a success clears nobody else's count, nor the address's
  const Guesser burnt{"10.0.0.9", "10.0.0.9:5000", 0};
  EXPECT_NE(b.refused_until(burnt, 4 * kS), 0);  // it guessed wrong: refused while the address is in back-off
  EXPECT_EQ(b.refused_until({"10.0.0.8", "10.0.0.8:1", 5 * kS}, 5 * kS), 0);  // another address is free
  EXPECT_EQ(b.refused_until(burnt, 12 * kS), 0);  // the address back-off (10 s) is over
}

TEST(AddressBackoff, AWrongGuessDuringTheAddressBackOffExtendsItAndTheRecordIsForgottenWhenQuiet) {
  AddressBackoff b;
  for (int i = 0; i < 5; ++i) b.wrong({"10.0.0.9", "10.0.0.9:" + std::to_string(5000 + i), 0}, kS);
  const Guesser patient{"10.0.0.9", "10.0.0.9:7000", 0};
  const auto l = b.wrong(patient, 3 * kS);  // heard (open 3 s), wrong: the address back-off starts again, twice as long
  EXPECT_TRUE(l.address_started);
  EXPECT_EQ(l.backoff_ns, 20 * kS);
  const Guesser late{"10.0.0.9", "10.0.0.9:7001", 3 * kS};
  EXPECT_NE(b.refused_until(late, 4 * kS), 0);
  const std::int64_t quiet = 3 * kS + AddressBackoff::kQuietNs;
  EXPECT_EQ(b.refused_until({"10.0.0.9", "10.0.0.9:7002", quiet}, quiet), 0);
  EXPECT_FALSE(b.wrong({"10.0.0.9", "10.0.0.9:7002", quiet}, quiet).started);  // the count started afresh
}

TEST(AddressBackoff, AnUnknownOpeningTimeStartsAtTheFirstGuessSeen) {
  AddressBackoff b;
  for (int i = 0; i < 5; ++i) b.wrong({"10.0.0.9", "10.0.0.9:" + std::to_string(5000 + i), -1}, kS);
  const Guesser http{"10.0.0.9", "10.0.0.9:8000", -1};
  EXPECT_EQ(b.refused_until(http, 2 * kS), 4 * kS);  // first seen now
  EXPECT_EQ(b.refused_until(http, 4 * kS), 0);       // the same keep-alive connection 2 s later
}

TEST(AddressBackoff, AClosedConnectionsCountGoesWithIt) {
  AddressBackoff b;
  const Guesser g{"10.0.0.9", "10.0.0.9:4000", 0};
  for (int i = 0; i < 4; ++i) b.wrong(g, kS);
  b.closed(g.connection);
  EXPECT_EQ(b.refused_until({"10.0.0.9", "10.0.0.9:4000", 2 * kS}, 2 * kS), 0);
}

}  // namespace
}  // namespace epa::core
