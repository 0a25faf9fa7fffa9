#pragma once
// One writer (the scan cycle) publishes a trivially copyable value; any number of readers
// (Modbus, web, store, logger threads) take consistent copies without ever blocking the writer.
// The value is stored as atomic words, so concurrent access is race-free by the C++ memory
// model. The words are stored with release and loaded with acquire rather than relaxed between
// fences: the same ordering (plain moves on x86), and ThreadSanitizer, which does not model
// fences (g++ refuses them under -fsanitize=thread), can check it.
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace epa::runtime {

template <typename T>
class SeqlockCell {
  static_assert(std::is_trivially_copyable_v<T>, "published values must be trivially copyable");
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;

 public:
  void publish(const T& value) noexcept {
    std::array<std::uint64_t, kWords> words{};
    std::memcpy(words.data(), &value, sizeof(T));
    const auto seq = sequence_.load(std::memory_order_relaxed);
    sequence_.store(seq + 1, std::memory_order_relaxed);  // odd: a write is in progress
    // Release: no word can become visible before the odd count above.
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(words[i], std::memory_order_release);
    sequence_.store(seq + 2, std::memory_order_release);
  }

  // Retries while a write is in progress; the writer publishes once per cycle, so this finishes.
  T read() const noexcept {
    std::array<std::uint64_t, kWords> words{};
    for (;;) {
      const auto before = sequence_.load(std::memory_order_acquire);
      if (before & 1u) continue;
      // Acquire: the check of the count below cannot move before any word is read.
      for (std::size_t i = 0; i < kWords; ++i) words[i] = words_[i].load(std::memory_order_acquire);
      if (sequence_.load(std::memory_order_relaxed) == before) break;
    }
    T value;
    std::memcpy(static_cast<void*>(&value), words.data(), sizeof(T));
    return value;
  }

  std::uint64_t version() const noexcept { return sequence_.load(std::memory_order_acquire) / 2; }

 private:
  std::atomic<std::uint64_t> sequence_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace epa::runtime
