#pragma once
// What stands between a client and guessing a secret (the Modbus unlock key, the HTTP token) at
// request speed, keyed so that a guesser is slowed without locking out the holder of the right
// secret on the same address (a shared HMI PC, a proxy):
//  - per connection: kFreeAttempts wrong guesses in a row, then that connection's guesses are
//    refused unseen for a back-off that starts at kFirstBackoffNs and doubles with each further
//    lock-out up to kMaxBackoffNs. A right guess clears that connection's record, nobody else's.
//  - per address: wrong guesses from all its connections count together; at kFreeAttempts the
//    address enters the same doubling back-off. A right guess does not clear it; the record is
//    forgotten after kQuietNs without a wrong guess. While the address is in back-off, a guess is
//    looked at only from a connection that has sent no wrong guess and has been open for
//    kQualifyNs (an HMI's or an engineer's session is; a guesser that reconnects never is).
//    So a guesser gets about one look per connection slot per kQualifyNs, and the right secret
//    sent on a connection open that long is always looked at.
// Records are bounded (the one seen longest ago goes first), so a flood of sources cannot grow
// them. Not thread-safe: the caller serialises.
#include <cstdint>
#include <string>
#include <unordered_map>

namespace epa::core {

// Who sends a guess.
struct Guesser {
  std::string address;         // the client's IP address
  std::string connection;      // one live connection, e.g. "ip:port"
  std::int64_t opened_ns = -1; // when it was opened; -1: unknown, the first guess seen on it counts
};

class AddressBackoff {
 public:
  static constexpr int kFreeAttempts = 5;
  static constexpr std::int64_t kFirstBackoffNs = 10'000'000'000;  // 10 s
  static constexpr std::int64_t kMaxBackoffNs = 300'000'000'000;   // 5 min
  static constexpr std::int64_t kQualifyNs = 2'000'000'000;        // 2 s open, no wrong guess: heard in an address back-off
  static constexpr std::int64_t kQuietNs = 600'000'000'000;        // 10 min without a wrong guess: the address is forgotten
  static constexpr std::size_t kMaxRecords = 4096;                 // of each kind

  // 0 when `who`'s guess at `now_ns` may be looked at, else the time until which it is refused unseen.
  std::int64_t refused_until(const Guesser& who, std::int64_t now_ns);

  struct Lockout {
    bool started = false;          // this wrong guess began a back-off of the connection or of the address
    bool address_started = false;  // ... of the address
    int wrong_in_row = 0;          // the connection's wrong guesses that led to it
    std::int64_t backoff_ns = 0;   // the connection's back-off (or the address's, when only that began)
  };
  Lockout wrong(const Guesser& who, std::int64_t now_ns);  // a wrong guess, looked at
  void right(const Guesser& who);                          // a right one: clears that connection's record only
  void closed(const std::string& connection);              // the connection is gone: its record too

 private:
  struct Streak {  // wrong guesses in a row and the back-off they earned
    int wrong_in_row = 0;
    std::int64_t locked_until_ns = 0;
    std::int64_t next_backoff_ns = kFirstBackoffNs;
    bool wrong(std::int64_t now_ns);  // true: a back-off began
  };
  struct ConnectionRecord {
    Streak streak;
    bool guessed_wrong = false;  // since its last right guess
    std::int64_t first_seen_ns = 0, last_seen_ns = 0;
  };
  struct AddressRecord {
    Streak streak;
    std::int64_t last_wrong_ns = 0, last_seen_ns = 0;
  };
  ConnectionRecord& connection(const Guesser& who, std::int64_t now_ns);
  AddressRecord* address(const std::string& address, std::int64_t now_ns);  // nullptr: none, or forgotten
  std::unordered_map<std::string, ConnectionRecord> connections_;
  std::unordered_map<std::string, AddressRecord> addresses_;
};

}  // namespace epa::core
