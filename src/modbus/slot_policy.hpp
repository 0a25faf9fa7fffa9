#pragma once
// Who gets a Modbus connection slot when a new client connects: fair slots, so that clients which
// look busy (read every second, reconnect when evicted) cannot push out the plant's HMI.
//  - With a free slot, a newcomer is admitted, whoever it is. max_per_address is a share, not a
//    wall: a crowd that holds its address's share cannot keep out the engineer or the HMI on that
//    address while there is room (a hard cap let 4 reading connections deny their whole address).
//  - A client that has proved itself is never evicted for a newcomer: it holds the unlock, or its
//    address is on write_clients, or it is among the longest-serving clients (open kHistoryNs with
//    a valid request in the last kHistoryNs; at most half the slots, and an address's share each,
//    are held this way, so a newcomer can always find room unless unlocked or write_clients
//    connections fill the server).
//  - When the server is full, a newcomer whose address already holds its share takes the place of
//    a client of its own address that has not proved itself, or is refused (closed at once): it
//    never evicts another address's client. Any other newcomer evicts a client that has not proved
//    itself: one of an address that holds its whole share first; then one that never completed a
//    request (the one silent the longest), else the youngest (so a reconnecting crowd churns among
//    its newest members while the established clients stay). A client arriving (kArrivalNs) is
//    not evicted, and while one arrives neither is an answered one. With none such, the newcomer
//    is refused. An address below its share is not preferred for holding more slots than others:
//    an HMI PC with an HMI, a historian and an engineering tool would then lose its youngest to
//    every newcomer.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace epa::modbus {

// A connected client as the policy sees it.
struct SlotHolder {
  std::string address;
  std::int64_t connected_ns = 0;
  std::int64_t last_valid_ns = -1;  // its last request answered without an exception; -1: none yet
  bool served = false;              // has completed a request (valid or not)
  bool proved = false;              // unlocked, or its address is on write_clients
};

struct SlotLimits {
  int max_clients = 16;
  int max_per_address = 4;
};

struct Admission {
  enum class Kind { kAdmit, kEvict, kRefuse } kind = Kind::kAdmit;
  std::size_t victim = 0;  // kEvict: the index of the client to close first
  const char* why = "";    // kRefuse: the rule that refused it
};

inline constexpr std::int64_t kHistoryNs = 10'000'000'000; // connected this long with valid requests: proved
// A client connected less than this long ago and not yet answered, of an address within its share,
// is arriving: its first request is on its way (one round trip on a plant network). It is not
// evicted, and while one is arriving no answered client is evicted either, only silent ones: a crowd that connects at once cannot
// push out a working HMI, and a reconnecting crowd cannot evict a connect-per-poll HMI between
// its connect and its answer (it did, in 1 of about 80 polls, before this rule).
inline constexpr std::int64_t kArrivalNs = 50'000'000;

// What to do with a newcomer from `address` at `now_ns`, given the connected `clients` in the order
// they were accepted.
Admission admit(std::span<const SlotHolder> clients, const std::string& address, std::int64_t now_ns, const SlotLimits& limits);

}  // namespace epa::modbus
