#pragma once
// The Modbus unlock: a 64-bit key (16 hex digits in the configuration, written as a key64: four
// holding registers, most significant first), guarded against brute force by the per-address
// back-off (core/address_backoff.hpp), keyed per connection plus per address: after 5 wrong keys a
// connection's unlock writes are refused without a look at the key, and after 5 from an address its
// writes are looked at only from connections open 2 s that sent no wrong key. Every refused attempt
// counts in failures(). The unlock itself belongs to the connection that sent the key (Session), so
// no other client gains from it, and ends when that connection closes or the unlock timeout runs out.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/address_backoff.hpp"
#include "core/result.hpp"

namespace epa::modbus {

// "0123abcd..." (16 hex digits) -> the key. Refused: another length, a non-hex digit, and keys an
// attacker tries first (fewer than 6 different digits, a digit run such as 0123456789abcdef, or a
// repeated pattern such as abababab..., mostly hex words such as deadbeefcafebabe:
// core/secret_strength.hpp).
core::Result<std::uint64_t> parse_unlock_key(std::string_view text);

class UnlockGuard {
 public:
  enum class Verdict { kUnlocked, kWrongKey, kLockedOut, kNoKey };
  struct Attempt {
    Verdict verdict = Verdict::kNoKey;
    bool lockout_started = false;  // this attempt began a back-off (log and audit it)
    bool address_lockout = false;  // ... of the whole address
    std::int64_t backoff_ns = 0;   // its length
  };

  explicit UnlockGuard(std::optional<std::uint64_t> key) : key_(key) {}

  // One unlock write from `who` (the client's address and connection) at `now_ns`.
  Attempt attempt(const core::Guesser& who, std::uint64_t key, std::int64_t now_ns);
  // The connection is gone: its own count goes with it (the address's stays).
  void closed(const std::string& connection) { backoff_.closed(connection); }

  std::uint64_t failures() const { return failures_; }

 private:
  std::optional<std::uint64_t> key_;
  core::AddressBackoff backoff_;
  std::uint64_t failures_ = 0;
};

}  // namespace epa::modbus
