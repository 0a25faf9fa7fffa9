#pragma once
// Commands in: a bounded ring whose consumer (the scan cycle) never blocks or allocates.
// Producers (Modbus, web, command line) serialise among themselves with a mutex, so a slow
// producer can only delay another producer, never the loop. A full queue refuses the push and
// the producer reports it (Modbus: exception 04).
#include <mutex>

#include "runtime/spsc_ring.hpp"

namespace epa::runtime {

template <typename T, std::size_t Capacity>
class CommandQueue {
 public:
  bool try_push(const T& item) {
    std::lock_guard lock(producer_mutex_);
    return ring_.try_push(item);
  }
  // A group (e.g. the points of one Modbus block write) arrives whole, in one cycle, or not at all.
  bool try_push_all(const T* items, std::size_t n) {
    std::lock_guard lock(producer_mutex_);
    return ring_.try_push_all(items, n);
  }
  bool try_pop(T& out) noexcept { return ring_.try_pop(out); }

 private:
  std::mutex producer_mutex_;
  SpscRing<T, Capacity> ring_;
};

}  // namespace epa::runtime
