// Work for the web workers is taken one item per address in turn, so one poll is not served after a
// crowd's backlog from other addresses.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "web/round_robin_by_key.hpp"

namespace epa::web {
namespace {

TEST(RoundRobinByKey, ALatePushFromANewKeyIsTakenAfterOneItemPerOtherKey) {
  RoundRobinByKey<int> q;
  for (int i = 0; i < 100; ++i) q.push("crowd-" + std::to_string(i % 3), i);  // 3 keys, 100 items
  q.push("poller", -1);
  std::vector<int> order;
  while (auto item = q.pop()) order.push_back(*item);
  ASSERT_EQ(order.size(), 101u);
  const auto at = std::find(order.begin(), order.end(), -1) - order.begin();
  EXPECT_LE(at, 3);  // behind at most one item of each crowd key
}

TEST(RoundRobinByKey, EachKeysItemsKeepTheirOrder) {
  RoundRobinByKey<int> q;
  q.push("a", 1), q.push("b", 10), q.push("a", 2), q.push("a", 3), q.push("b", 20);
  std::vector<int> order;
  while (auto item = q.pop()) order.push_back(*item);
  EXPECT_EQ(order, (std::vector<int>{1, 10, 2, 20, 3}));
  EXPECT_EQ(q.size(), 0u);
  EXPECT_FALSE(q.pop().has_value());
}

TEST(RoundRobinByKey, AKeyThatEmptiedJoinsTheTurnsAgainAtTheBack) {
  RoundRobinByKey<int> q;
  q.push("a", 1), q.push("b", 2);
  EXPECT_EQ(*q.pop(), 1);  // a empties and leaves the turns
  q.push("c", 3), q.push("a", 4);
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(*q.pop(), 2);
  EXPECT_EQ(*q.pop(), 3);
  EXPECT_EQ(*q.pop(), 4);
}

}  // namespace
}  // namespace epa::web
