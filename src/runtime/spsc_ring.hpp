#pragma once
// A bounded single-producer single-consumer ring: wait-free on both sides, no allocation after
// construction. The scan cycle uses it to hand events to the recorder thread.
#include <array>
#include <atomic>
#include <cstddef>

namespace epa::runtime {

template <typename T, std::size_t Capacity>
class SpscRing {
  static_assert((Capacity & (Capacity - 1)) == 0, "capacity must be a power of two");

 public:
  bool try_push(const T& item) noexcept {
    const auto tail = tail_.load(std::memory_order_relaxed);
    if (tail - head_.load(std::memory_order_acquire) == Capacity) return false;
    slots_[tail & (Capacity - 1)] = item;
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // All of `items` or none, published with one store: the consumer sees the whole group at once.
  bool try_push_all(const T* items, std::size_t n) noexcept {
    const auto tail = tail_.load(std::memory_order_relaxed);
    if (Capacity - (tail - head_.load(std::memory_order_acquire)) < n) return false;
    for (std::size_t i = 0; i < n; ++i) slots_[(tail + i) & (Capacity - 1)] = items[i];
    tail_.store(tail + n, std::memory_order_release);
    return true;
  }

  bool try_pop(T& out) noexcept {
    const auto head = head_.load(std::memory_order_relaxed);
    if (head == tail_.load(std::memory_order_acquire)) return false;
    out = slots_[head & (Capacity - 1)];
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

 private:
  std::atomic<std::size_t> head_{0}, tail_{0};
  std::array<T, Capacity> slots_{};
};

}  // namespace epa::runtime
