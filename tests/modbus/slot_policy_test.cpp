// Fair Modbus connection slots (slot_policy.hpp), decided without sockets.
#include "modbus/slot_policy.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace epa::modbus {
namespace {

constexpr std::int64_t kS = 1'000'000'000;
using Kind = Admission::Kind;

SlotHolder busy(const std::string& address, std::int64_t connected_ns, std::int64_t now_ns) {
  return {address, connected_ns, now_ns - kS / 2, true, false};
}

TEST(SlotPolicy, BelowTheCapsANewcomerIsAdmitted) {
  const std::vector<SlotHolder> c = {busy("10.0.0.1", 0, kS)};
  EXPECT_EQ(admit(c, "10.0.0.2", kS, {2, 4}).kind, Kind::kAdmit);
}

TEST(SlotPolicy, WhenFullTheYoungestUnprovedClientGoesNotTheEstablishedOne) {
  const std::int64_t now = 5 * kS;
  const std::vector<SlotHolder> c = {busy("10.0.0.1", 0, now), busy("10.0.0.2", 2 * kS, now), busy("10.0.0.3", 4 * kS, now)};
  const Admission a = admit(c, "10.0.0.4", now, {3, 4});
  EXPECT_EQ(a.kind, Kind::kEvict);
  EXPECT_EQ(a.victim, 2u);
}

TEST(SlotPolicy, ASilentClientGoesFirstTheOneSilentTheLongest) {
  const std::int64_t now = 5 * kS;
  std::vector<SlotHolder> c = {busy("10.0.0.1", 0, now), {"10.0.0.2", 1 * kS, -1, false, false}, {"10.0.0.3", 3 * kS, -1, false, false}};
  EXPECT_EQ(admit(c, "10.0.0.4", now, {3, 4}).victim, 1u);
}

// A connect-per-poll HMI is the newest, unanswered client for the ms its poll takes: a
// reconnecting attacker must not evict it then, nor anyone answered (a crowd arriving at once).
TEST(SlotPolicy, WhileAClientIsArrivingOnlySilentClientsAreEvicted) {
  const std::int64_t now = 5 * kS;
  std::vector<SlotHolder> c = {busy("10.0.0.1", 1 * kS, now), busy("10.0.0.2", 3 * kS, now),
                               {"127.0.0.1", now - kArrivalNs / 10, -1, false, false}};
  const Admission refused = admit(c, "10.0.0.9", now, {3, 4});
  EXPECT_EQ(refused.kind, Kind::kRefuse);
  EXPECT_STREQ(refused.why, "full while other clients are arriving: try again");
  c.push_back({"10.0.0.3", 2 * kS, -1, false, false});  // silent for 3 s: it goes
  const Admission a = admit(c, "10.0.0.9", now, {4, 4});
  EXPECT_EQ(a.kind, Kind::kEvict);
  EXPECT_EQ(a.victim, 3u);
  // Unanswered past the arrival time, it is silent and the one silent the longest goes.
  c.pop_back();
  EXPECT_EQ(admit(c, "10.0.0.9", now + kArrivalNs, {3, 4}).victim, 2u);
}

// A burst of silent connects from one address is beyond its share: not shielded as arriving, so
// the client that comes after the burst gets a slot.
TEST(SlotPolicy, ABurstFromOneAddressIsNotShieldedAsArriving) {
  const std::int64_t now = 5 * kS;
  std::vector<SlotHolder> c = {busy("10.0.0.1", 1 * kS, now)};
  for (int i = 0; i < 5; ++i) c.push_back({"10.0.0.7", now - kArrivalNs / 2 + i, -1, false, false});
  const Admission a = admit(c, "10.0.0.9", now, {6, 4});
  EXPECT_EQ(a.kind, Kind::kEvict);
  EXPECT_EQ(a.victim, 1u);  // of the burst's address (over its share), the one silent the longest
}

TEST(SlotPolicy, ProvedClientsStayAndWithNoneElseTheNewcomerIsRefused) {
  const std::int64_t now = 20 * kS;
  std::vector<SlotHolder> c = {busy("10.0.0.1", 19 * kS, now), busy("10.0.0.2", 19 * kS, now)};
  c[0].proved = c[1].proved = true;  // unlocked, or on write_clients
  EXPECT_EQ(admit(c, "10.0.0.3", now, {2, 4}).kind, Kind::kRefuse);
}

TEST(SlotPolicy, LongServingClientsHoldAtMostHalfTheSlots) {
  const std::int64_t now = 30 * kS;
  std::vector<SlotHolder> c;
  for (int i = 0; i < 4; ++i) c.push_back(busy("10.0.0." + std::to_string(i + 1), i * kS, now));  // all open >= 10 s
  const Admission a = admit(c, "10.0.0.9", now, {4, 4});
  EXPECT_EQ(a.kind, Kind::kEvict);
  EXPECT_EQ(a.victim, 3u);  // the two longest-serving are kept; of the others, the youngest goes
  c[2].proved = c[3].proved = true;
  EXPECT_EQ(admit(c, "10.0.0.9", now, {4, 4}).kind, Kind::kRefuse);
}

TEST(SlotPolicy, WhenFullANewcomerAboveItsAddressShareReplacesItsOwnAddressesClientOrIsRefused) {
  const std::int64_t now = 5 * kS;
  std::vector<SlotHolder> c = {busy("10.0.0.1", 0, now), busy("10.0.0.2", 1 * kS, now), busy("10.0.0.2", 2 * kS, now)};
  const Admission a = admit(c, "10.0.0.2", now, {3, 2});
  EXPECT_EQ(a.kind, Kind::kEvict);
  EXPECT_EQ(a.victim, 2u);  // its own address's youngest, not the younger-looking other address
  c[1].proved = c[2].proved = true;
  EXPECT_EQ(admit(c, "10.0.0.2", now, {3, 2}).kind, Kind::kRefuse);
}

// Four connections that read every second held their address's whole share, and the engineer on
// that address could not connect at all (an outside test: 0 of 30 unlocks).
TEST(SlotPolicy, WithRoomAnAddressAboveItsShareIsAdmitted) {
  const std::int64_t now = 30 * kS;
  std::vector<SlotHolder> c;
  for (int i = 0; i < 4; ++i) c.push_back(busy("10.0.0.2", i * kS, now));  // long-serving, all of them
  EXPECT_EQ(admit(c, "10.0.0.2", now, {16, 4}).kind, Kind::kAdmit);
}

TEST(SlotPolicy, AnAddressHoldsAtMostItsShareOfTheLongServingSlots) {
  const std::int64_t now = 30 * kS;
  std::vector<SlotHolder> c;
  for (int i = 0; i < 6; ++i) c.push_back(busy("10.0.0.2", i * kS, now));  // six long-serving from one address
  c.push_back(busy("10.0.0.3", 25 * kS, now));
  c.push_back(busy("10.0.0.4", 26 * kS, now));
  const Admission a = admit(c, "10.0.0.9", now, {8, 4});
  EXPECT_EQ(a.kind, Kind::kEvict);
  EXPECT_EQ(a.victim, 5u);  // only 4 of 10.0.0.2's count as long-serving; its youngest goes (it is over its share)
}

TEST(SlotPolicy, AnAddressHoldingItsWholeShareGivesUpASlotBeforeOthers) {
  const std::int64_t now = 5 * kS;
  const std::vector<SlotHolder> c = {busy("10.0.0.1", 1 * kS, now), busy("10.0.0.1", 2 * kS, now), busy("10.0.0.2", 4 * kS, now)};
  EXPECT_EQ(admit(c, "10.0.0.3", now, {3, 2}).victim, 1u);  // 10.0.0.1 holds its 2: its youngest, not the younger 10.0.0.2
}

}  // namespace
}  // namespace epa::modbus
