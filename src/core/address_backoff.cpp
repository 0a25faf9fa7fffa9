#include "core/address_backoff.hpp"

#include <algorithm>

namespace epa::core {

AddressBackoff::Record& AddressBackoff::record(const std::string& address, std::int64_t now_ns) {
  if (records_.size() >= kMaxAddresses && !records_.contains(address)) {
    auto oldest = std::min_element(records_.begin(), records_.end(),
                                   [](const auto& a, const auto& b) { return a.second.last_seen_ns < b.second.last_seen_ns; });
    records_.erase(oldest);
  }
  Record& r = records_[address];
  r.last_seen_ns = now_ns;
  return r;
}

std::int64_t AddressBackoff::locked_until(const std::string& address, std::int64_t now_ns) {
  const auto it = records_.find(address);
  if (it == records_.end() || now_ns >= it->second.locked_until_ns) return 0;
  it->second.last_seen_ns = now_ns;
  return it->second.locked_until_ns;
}

AddressBackoff::Lockout AddressBackoff::wrong(const std::string& address, std::int64_t now_ns) {
  Record& r = record(address, now_ns);
  if (++r.wrong_in_row < kFreeAttempts) return {};
  // The next wrong guess after this back-off locks out again, twice as long.
  const Lockout l{true, r.wrong_in_row, r.next_backoff_ns};
  r.locked_until_ns = now_ns + r.next_backoff_ns;
  r.next_backoff_ns = std::min(r.next_backoff_ns * 2, kMaxBackoffNs);
  r.wrong_in_row = kFreeAttempts - 1;
  return l;
}

void AddressBackoff::right(const std::string& address) { records_.erase(address); }

}  // namespace epa::core
