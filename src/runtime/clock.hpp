#pragma once
// The scan cycle's time source. MonotonicClock sleeps to absolute deadlines on CLOCK_MONOTONIC
// (no drift from accumulated relative sleeps); VirtualClock jumps to the deadline at once, so
// tests run the same loop deterministically and thousands of times faster than real time.
#include <cstdint>

namespace epa::runtime {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual std::int64_t now_ns() noexcept = 0;
  virtual void sleep_until(std::int64_t deadline_ns) noexcept = 0;
};

class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() noexcept override;
  void sleep_until(std::int64_t deadline_ns) noexcept override;  // clock_nanosleep TIMER_ABSTIME, EINTR-safe
};

class VirtualClock final : public Clock {
 public:
  std::int64_t now_ns() noexcept override { return now_ns_; }
  void sleep_until(std::int64_t deadline_ns) noexcept override {
    if (deadline_ns > now_ns_) now_ns_ = deadline_ns;
  }
  void advance(std::int64_t ns) noexcept { now_ns_ += ns; }  // simulates compute time or a stall

 private:
  std::int64_t now_ns_ = 0;
};

}  // namespace epa::runtime
