#include "modbus/unlock_guard.hpp"

#include <algorithm>
#include <set>

namespace epa::modbus {

core::Result<std::uint64_t> parse_unlock_key(std::string_view text) {
  auto refuse = [](const std::string& why) {
    return core::invalid_argument(why + ": give 16 random hex digits, e.g. from `od -An -tx8 -N8 /dev/urandom`");
  };
  if (text.size() != 16) return refuse("must be 16 hex digits, got " + std::to_string(text.size()) + " characters");
  std::uint64_t key = 0;
  std::string digits;
  for (char c : text) {
    const char lower = static_cast<char>(c >= 'A' && c <= 'F' ? c - 'A' + 'a' : c);
    int v = -1;
    if (lower >= '0' && lower <= '9') v = lower - '0';
    else if (lower >= 'a' && lower <= 'f') v = lower - 'a' + 10;
    if (v < 0) return refuse(std::string("has '") + c + "', not a hex digit");
    key = key << 4 | static_cast<std::uint64_t>(v);
    digits += lower;
  }
  if (std::set<char>(digits.begin(), digits.end()).size() < 6) return refuse("has fewer than 6 different digits: too easy to guess");
  for (std::size_t period = 1; period <= 8; ++period) {
    bool repeats = true;
    for (std::size_t i = period; i < digits.size() && repeats; ++i) repeats = digits[i] == digits[i - period];
    if (repeats) return refuse("repeats a pattern of " + std::to_string(period) + " digits: too easy to guess");
  }
  int up = 0, down = 0;
  for (std::size_t i = 1; i < digits.size(); ++i) {
    const auto value = [&](std::size_t j) { return digits[j] <= '9' ? digits[j] - '0' : digits[j] - 'a' + 10; };
    up += value(i) == value(i - 1) + 1;
    down += value(i) == value(i - 1) - 1;
  }
  if (up >= 8 || down >= 8) return refuse("is mostly a run of consecutive digits: too easy to guess");
  return key;
}

UnlockGuard::Attempt UnlockGuard::attempt(const std::string& address, std::uint64_t key, std::int64_t now_ns) {
  if (!key_) {
    ++failures_;
    return {Verdict::kNoKey};
  }
  if (records_.size() >= kMaxAddresses && !records_.contains(address)) {
    // Bounded: forget the address seen longest ago (a flood of spoofed sources cannot grow it).
    auto oldest = std::min_element(records_.begin(), records_.end(),
                                   [](const auto& a, const auto& b) { return a.second.last_seen_ns < b.second.last_seen_ns; });
    records_.erase(oldest);
  }
  Record& r = records_[address];
  r.last_seen_ns = now_ns;
  if (now_ns < r.locked_until_ns) {
    ++failures_;
    return {Verdict::kLockedOut, false, 0, r.locked_until_ns};
  }
  if (key == *key_) {
    records_.erase(address);
    return {Verdict::kUnlocked};
  }
  ++failures_;
  if (++r.wrong_in_row < kFreeAttempts) return {Verdict::kWrongKey};
  // Locked out: from now on this address's attempts are refused unseen until the back-off ends;
  // the next wrong key after it locks out again, twice as long.
  Attempt a{Verdict::kWrongKey, true, r.next_backoff_ns, now_ns + r.next_backoff_ns};
  r.locked_until_ns = a.locked_until_ns;
  r.next_backoff_ns = std::min(r.next_backoff_ns * 2, kMaxBackoffNs);
  r.wrong_in_row = kFreeAttempts - 1;
  return a;
}

}  // namespace epa::modbus
