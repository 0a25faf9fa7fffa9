#pragma once
// Waiting for something to happen instead of sleeping a fixed time and hoping it has: a bounded
// poll of a predicate. A fixed sleep is either too short on a loaded machine (a flaky test) or
// longer than needed everywhere else (a slow one); the poll returns as soon as the predicate holds
// and gives up at a deadline far above what the wait takes on an idle machine. The caller then
// asserts what it asserted before, so a wait that timed out fails where the old sleep would have.
#include <chrono>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

namespace epa::test {

// Polls holds() every `every` until it returns true or `timeout` has passed; returns whether it
// held (checked once more at the deadline).
template <class Predicate>
bool wait_until(Predicate&& holds, std::chrono::milliseconds timeout = std::chrono::milliseconds(5000),
                std::chrono::milliseconds every = std::chrono::milliseconds(1)) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (holds()) return true;
    if (std::chrono::steady_clock::now() >= until) return holds();
    std::this_thread::sleep_for(every);
  }
}

// How many connections wait in the accept queue of the listening TCP socket on `port` (any local
// address, IPv4 or IPv6): the rx_queue of its LISTEN row in /proc/net/tcp{,6}. 0 once the server
// has accepted every connection made to it; -1 when no socket listens on the port.
inline int accept_queue_length(int port) {
  for (const char* table : {"/proc/net/tcp", "/proc/net/tcp6"}) {
    std::ifstream in(table);
    std::string line;
    std::getline(in, line);  // the header
    while (std::getline(in, line)) {
      std::istringstream row(line);
      std::string slot, local, remote, state, queues;
      if (!(row >> slot >> local >> remote >> state >> queues)) continue;
      if (state != "0A") continue;  // TCP_LISTEN
      const auto colon = local.rfind(':');
      if (colon == std::string::npos || std::stoi(local.substr(colon + 1), nullptr, 16) != port) continue;
      const auto q = queues.find(':');
      if (q == std::string::npos) continue;
      return static_cast<int>(std::stoul(queues.substr(q + 1), nullptr, 16));  // tx_queue:rx_queue
    }
  }
  return -1;
}

}  // namespace epa::test
