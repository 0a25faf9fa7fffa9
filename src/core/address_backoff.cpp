#include "core/address_backoff.hpp"

#include <algorithm>

namespace epa::core {

namespace {
// Room for one more record: the one seen longest ago goes.
template <typename Map>
void make_room(Map& records, const std::string& key) {
  if (records.size() < AddressBackoff::kMaxRecords || records.contains(key)) return;
  records.erase(std::min_element(records.begin(), records.end(),
                                 [](const auto& a, const auto& b) { return a.second.last_seen_ns < b.second.last_seen_ns; }));
}
}  // namespace

bool AddressBackoff::Streak::wrong(std::int64_t now_ns) {
  if (++wrong_in_row < kFreeAttempts) return false;
  // The next wrong guess after this back-off locks out again, twice as long.
  locked_until_ns = now_ns + next_backoff_ns;
  next_backoff_ns = std::min(next_backoff_ns * 2, kMaxBackoffNs);
  wrong_in_row = kFreeAttempts - 1;
  return true;
}

AddressBackoff::ConnectionRecord& AddressBackoff::connection(const Guesser& who, std::int64_t now_ns) {
  make_room(connections_, who.connection);
  auto [it, fresh] = connections_.try_emplace(who.connection);
  if (fresh) it->second.first_seen_ns = now_ns;
  it->second.last_seen_ns = now_ns;
  return it->second;
}

AddressBackoff::AddressRecord* AddressBackoff::address(const std::string& address, std::int64_t now_ns) {
  const auto it = addresses_.find(address);
  if (it == addresses_.end()) return nullptr;
  if (now_ns >= it->second.streak.locked_until_ns && now_ns - it->second.last_wrong_ns >= kQuietNs) {
    addresses_.erase(it);  // quiet long enough: its wrong guesses are forgotten
    return nullptr;
  }
  it->second.last_seen_ns = now_ns;
  return &it->second;
}

std::int64_t AddressBackoff::refused_until(const Guesser& who, std::int64_t now_ns) {
  // An unknown opening time is the first guess seen on the connection: its record starts the clock.
  ConnectionRecord* conn = nullptr;
  if (who.opened_ns < 0) {
    conn = &connection(who, now_ns);
  } else if (const auto it = connections_.find(who.connection); it != connections_.end()) {
    conn = &it->second;
  }
  if (conn && now_ns < conn->streak.locked_until_ns) return conn->streak.locked_until_ns;
  const AddressRecord* addr = address(who.address, now_ns);
  if (!addr || now_ns >= addr->streak.locked_until_ns) return 0;
  // The address is in back-off: heard only from a connection with no wrong guess, open kQualifyNs.
  if (conn && conn->guessed_wrong) return addr->streak.locked_until_ns;
  const std::int64_t opened_ns = who.opened_ns >= 0 ? who.opened_ns : conn->first_seen_ns;
  if (now_ns - opened_ns >= kQualifyNs) return 0;
  return std::min(opened_ns + kQualifyNs, addr->streak.locked_until_ns);
}

AddressBackoff::Lockout AddressBackoff::wrong(const Guesser& who, std::int64_t now_ns) {
  ConnectionRecord& conn = connection(who, now_ns);
  conn.guessed_wrong = true;
  Lockout l;
  l.started = conn.streak.wrong(now_ns);
  l.wrong_in_row = l.started ? kFreeAttempts : conn.streak.wrong_in_row;
  if (l.started) l.backoff_ns = conn.streak.locked_until_ns - now_ns;

  AddressRecord* addr = address(who.address, now_ns);
  if (!addr) {
    make_room(addresses_, who.address);
    addr = &addresses_[who.address];
    addr->last_seen_ns = now_ns;
  }
  addr->last_wrong_ns = now_ns;
  l.address_started = addr->streak.wrong(now_ns);
  if (l.address_started && !l.started) l.backoff_ns = addr->streak.locked_until_ns - now_ns;
  l.started = l.started || l.address_started;
  return l;
}

void AddressBackoff::right(const Guesser& who) { connections_.erase(who.connection); }

void AddressBackoff::closed(const std::string& connection) { connections_.erase(connection); }

}  // namespace epa::core
