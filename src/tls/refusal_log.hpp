#pragma once
// Handshake refusals, told once per address with a back-off: a client with a bad certificate (or
// a scanner sending garbage) reconnects in a loop, and a line per attempt would fill the disk and
// hide the first, useful one. An address's first refusal is told at once with the reason; the next
// after kFirstBackoffNs, then after twice that, up to kMaxBackoffNs, each with the count of the
// refusals not told in between. An address quiet for kForgetNs starts over. The records are
// bounded (the one seen longest ago goes first). Not thread-safe: a server's one thread uses it.
#include <algorithm>
#include <cstdint>
#include <string>
#include <unordered_map>

namespace epa::tls {

class RefusalLog {
 public:
  static constexpr std::int64_t kFirstBackoffNs = 60'000'000'000;
  static constexpr std::int64_t kMaxBackoffNs = 3600'000'000'000;
  static constexpr std::int64_t kForgetNs = 2 * kMaxBackoffNs;
  static constexpr std::size_t kMaxAddresses = 1024;

  // The line to log for a refusal of `address` for `why` at `now_ns`; "" when it is held back.
  std::string refused(const std::string& address, const std::string& why, std::int64_t now_ns) {
    auto it = records_.find(address);
    if (it != records_.end() && now_ns - it->second.last_ns > kForgetNs) records_.erase(it), it = records_.end();
    if (it == records_.end()) {
      if (records_.size() >= kMaxAddresses) forget_oldest();
      records_[address] = {now_ns + kFirstBackoffNs, kFirstBackoffNs, 0, now_ns};
      return address + " refused in the TLS handshake: " + why;
    }
    Record& r = it->second;
    r.last_ns = now_ns;
    if (now_ns < r.next_line_ns) return ++r.held_back, "";
    const std::uint64_t held = r.held_back;
    r.held_back = 0;
    r.backoff_ns = std::min(2 * r.backoff_ns, kMaxBackoffNs);
    r.next_line_ns = now_ns + r.backoff_ns;
    return address + " refused in the TLS handshake: " + why + " (and " + std::to_string(held) +
           " refusals from it not logged since; next line in " + std::to_string(r.backoff_ns / 1'000'000'000) + " s at the earliest)";
  }
  std::size_t addresses() const { return records_.size(); }

 private:
  struct Record {
    std::int64_t next_line_ns = 0;
    std::int64_t backoff_ns = 0;
    std::uint64_t held_back = 0;
    std::int64_t last_ns = 0;
  };
  void forget_oldest() {
    auto oldest = records_.begin();
    for (auto it = records_.begin(); it != records_.end(); ++it)
      if (it->second.last_ns < oldest->second.last_ns) oldest = it;
    records_.erase(oldest);
  }
  std::unordered_map<std::string, Record> records_;
};

}  // namespace epa::tls
