#pragma once
// What stands between a client and guessing a secret (the Modbus unlock key, the HTTP token) at
// request speed: after kFreeAttempts wrong guesses in a row from one address, that address is
// refused unseen for a back-off that starts at kFirstBackoffNs and doubles with each further
// lock-out up to kMaxBackoffNs; a right guess outside a back-off clears its record. Records are
// bounded (the address seen longest ago goes first), so a flood of sources cannot grow them.
// Not thread-safe: the caller serialises.
#include <cstdint>
#include <string>
#include <unordered_map>

namespace epa::core {

class AddressBackoff {
 public:
  static constexpr int kFreeAttempts = 5;
  static constexpr std::int64_t kFirstBackoffNs = 10'000'000'000;  // 10 s
  static constexpr std::int64_t kMaxBackoffNs = 300'000'000'000;   // 5 min
  static constexpr std::size_t kMaxAddresses = 4096;

  // 0 when `address` may guess at `now_ns`, else the time its back-off ends.
  std::int64_t locked_until(const std::string& address, std::int64_t now_ns);

  struct Lockout {
    bool started = false;     // this wrong guess began a back-off
    int wrong_in_row = 0;     // guesses that led to it
    std::int64_t backoff_ns = 0;
  };
  Lockout wrong(const std::string& address, std::int64_t now_ns);  // a wrong guess, looked at
  void right(const std::string& address);                            // a right one

 private:
  struct Record {
    int wrong_in_row = 0;
    std::int64_t locked_until_ns = 0;
    std::int64_t next_backoff_ns = kFirstBackoffNs;
    std::int64_t last_seen_ns = 0;
  };
  Record& record(const std::string& address, std::int64_t now_ns);
  std::unordered_map<std::string, Record> records_;
};

}  // namespace epa::core
