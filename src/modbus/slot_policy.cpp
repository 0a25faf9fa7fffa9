#include "modbus/slot_policy.hpp"

#include <algorithm>
#include <map>
#include <vector>

namespace epa::modbus {

namespace {

// Which clients hold their slot by history: open kHistoryNs with a valid request within the last
// kHistoryNs, the longest-connected first, at most half the slots and an address's share each.
std::vector<bool> proved_by_history(std::span<const SlotHolder> clients, std::int64_t now_ns, const SlotLimits& limits) {
  std::vector<std::size_t> veterans;
  for (std::size_t i = 0; i < clients.size(); ++i) {
    const SlotHolder& c = clients[i];
    if (now_ns - c.connected_ns >= kHistoryNs && c.last_valid_ns >= 0 && now_ns - c.last_valid_ns <= kHistoryNs) veterans.push_back(i);
  }
  std::sort(veterans.begin(), veterans.end(), [&](std::size_t a, std::size_t b) { return clients[a].connected_ns < clients[b].connected_ns; });
  std::vector<bool> kept(clients.size(), false);
  std::map<std::string, int> per_address;
  int kept_count = 0;
  for (std::size_t i : veterans) {
    if (kept_count >= limits.max_clients / 2) break;
    if (per_address[clients[i].address]++ >= limits.max_per_address) continue;
    kept[i] = true;
    ++kept_count;
  }
  return kept;
}

// Whether `a` goes before `b` (which was accepted earlier: on the same clock tick, `a` is younger):
// a client of an address that holds its whole share, then a client that never completed a request
// (silent the longest first), then the youngest.
bool evict_before(const SlotHolder& a, const SlotHolder& b, const std::map<std::string, int>& held, int max_per_address) {
  const bool a_full = held.at(a.address) >= max_per_address, b_full = held.at(b.address) >= max_per_address;
  if (a_full != b_full) return a_full;
  if (a.served != b.served) return !a.served;
  return a.served ? a.connected_ns >= b.connected_ns : a.connected_ns < b.connected_ns;
}

}  // namespace

Admission admit(std::span<const SlotHolder> clients, const std::string& address, std::int64_t now_ns, const SlotLimits& limits) {
  std::map<std::string, int> held;
  for (const SlotHolder& c : clients) ++held[c.address];
  // A share, not a wall: with room, anyone is admitted (so a crowd holding its address's share
  // cannot keep out the engineer or the HMI on that address); only a full server takes shares.
  if (static_cast<int>(clients.size()) < limits.max_clients) return {};
  const bool address_full = held[address] >= limits.max_per_address;

  const std::vector<bool> veteran = proved_by_history(clients, now_ns, limits);
  // Arriving clients of an address within its share: a burst of silent connects from one address
  // (a reconnect storm) is not shielded by the rule, and the client after it gets a slot.
  auto arriving = [&](const SlotHolder& c) {
    return !c.served && now_ns - c.connected_ns < kArrivalNs && held.at(c.address) <= limits.max_per_address;
  };
  const bool someone_arriving = std::any_of(clients.begin(), clients.end(), arriving);
  std::size_t pick = clients.size();
  for (std::size_t i = 0; i < clients.size(); ++i) {
    const SlotHolder& c = clients[i];
    if (c.proved || veteran[i] || (address_full && c.address != address)) continue;
    if (arriving(c) || (someone_arriving && c.served)) continue;
    if (pick == clients.size() || evict_before(c, clients[pick], held, limits.max_per_address)) pick = i;
  }
  if (pick < clients.size()) return {Admission::Kind::kEvict, pick, ""};
  if (someone_arriving) return {Admission::Kind::kRefuse, 0, "full while other clients are arriving: try again"};
  return {Admission::Kind::kRefuse, 0,
          address_full ? "max_clients_per_address reached, every client of that address proved"
                       : "max_clients reached, every client proved (unlocked, on write_clients or long-serving)"};
}

}  // namespace epa::modbus
