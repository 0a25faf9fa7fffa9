#include "modbus/unlock_guard.hpp"

#include <set>

#include "core/secret_strength.hpp"

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
  if (const std::string why = core::hex_words_weakness(digits); !why.empty()) return refuse(why);
  return key;
}

UnlockGuard::Attempt UnlockGuard::attempt(const core::Guesser& who, std::uint64_t key, std::int64_t now_ns) {
  if (!key_) {
    ++failures_;
    return {Verdict::kNoKey};
  }
  if (backoff_.refused_until(who, now_ns) != 0) {
    ++failures_;
    return {Verdict::kLockedOut};
  }
  if (key == *key_) {
    backoff_.right(who);
    return {Verdict::kUnlocked};
  }
  ++failures_;
  const auto lockout = backoff_.wrong(who, now_ns);
  return {Verdict::kWrongKey, lockout.started, lockout.address_started, lockout.backoff_ns};
}

}  // namespace epa::modbus
