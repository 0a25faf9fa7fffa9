#pragma once
// The Modbus unlock: a 64-bit key (16 hex digits in the configuration, written as a key64: four
// holding registers, most significant first) and what stands between a client and brute force.
// After kFreeAttempts wrong keys from one IP address, that address's unlock writes are refused
// without looking at the key for a back-off that starts at kFirstBackoff and doubles with each
// further lock-out, up to kMaxBackoff; a right key outside a back-off clears the address's
// record. Every refused attempt counts in failures(). The unlock itself belongs to the
// connection that sent the key (Session), so no other client gains from it, and ends when that
// connection closes or the unlock timeout runs out.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>

#include "core/result.hpp"

namespace epa::modbus {

// "0123abcd..." (16 hex digits) -> the key. Refused: another length, a non-hex digit, and keys an
// attacker tries first (fewer than 6 different digits, a digit run such as 0123456789abcdef, or a
// repeated pattern such as abababab...).
core::Result<std::uint64_t> parse_unlock_key(std::string_view text);

class UnlockGuard {
 public:
  static constexpr int kFreeAttempts = 5;
  static constexpr std::int64_t kFirstBackoffNs = 10'000'000'000;   // 10 s
  static constexpr std::int64_t kMaxBackoffNs = 300'000'000'000;    // 5 min
  static constexpr std::size_t kMaxAddresses = 4096;                 // records kept; the oldest go first

  enum class Verdict { kUnlocked, kWrongKey, kLockedOut, kNoKey };
  struct Attempt {
    Verdict verdict = Verdict::kNoKey;
    bool lockout_started = false;  // this attempt began a back-off (log and audit it)
    std::int64_t backoff_ns = 0;   // its length
    std::int64_t locked_until_ns = 0;
  };

  explicit UnlockGuard(std::optional<std::uint64_t> key) : key_(key) {}

  // One unlock write from `address` (the client's IP) at `now_ns`.
  Attempt attempt(const std::string& address, std::uint64_t key, std::int64_t now_ns);

  std::uint64_t failures() const { return failures_; }

 private:
  struct Record {
    int wrong_in_row = 0;
    std::int64_t locked_until_ns = 0;
    std::int64_t next_backoff_ns = kFirstBackoffNs;
    std::int64_t last_seen_ns = 0;
  };
  std::optional<std::uint64_t> key_;
  std::unordered_map<std::string, Record> records_;
  std::uint64_t failures_ = 0;
};

}  // namespace epa::modbus
