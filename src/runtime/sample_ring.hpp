#pragma once
// The run recorder's memory: every sample of the loop (t, r, y, u, controller output) in a ring
// allocated once. The loop writes; the recorder thread copies a range out later and checks that
// the loop has not overwritten it meanwhile. Fields are relaxed atomics, so the overlap is a
// detected condition, not a data race.
#include <atomic>
#include <cstdint>
#include <memory>

#include "core/run.hpp"

namespace epa::runtime {

struct RecordedSample {
  double t_s, r_mm, y_mm, u_v, uc_v;
};

class SampleRing {
 public:
  explicit SampleRing(std::size_t capacity) : capacity_(capacity), slots_(std::make_unique<Slot[]>(capacity)) {}

  std::size_t capacity() const { return capacity_; }
  std::uint64_t written() const noexcept { return written_.load(std::memory_order_acquire); }  // samples so far

  void push(const RecordedSample& s) noexcept {
    const auto index = written_.load(std::memory_order_relaxed);
    Slot& slot = slots_[index % capacity_];
    slot.t_s.store(s.t_s, std::memory_order_relaxed);
    slot.r_mm.store(s.r_mm, std::memory_order_relaxed);
    slot.y_mm.store(s.y_mm, std::memory_order_relaxed);
    slot.u_v.store(s.u_v, std::memory_order_relaxed);
    slot.uc_v.store(s.uc_v, std::memory_order_relaxed);
    written_.store(index + 1, std::memory_order_release);
  }

  // Samples [first, end) appended to `run` (which allocates: call off the loop). Samples already
  // overwritten are skipped; returns the index of the first sample copied.
  std::uint64_t copy_out(std::uint64_t first, std::uint64_t end, core::Run& run) const {
    const auto oldest = [&] { const auto w = written(); return w > capacity_ ? w - capacity_ : 0; };
    first = std::max(first, oldest());
    for (auto k = first; k < end; ++k) {
      const Slot& slot = slots_[k % capacity_];
      run.t_s.push_back(slot.t_s.load(std::memory_order_relaxed));
      run.r_mm.push_back(slot.r_mm.load(std::memory_order_relaxed));
      run.y_mm.push_back(slot.y_mm.load(std::memory_order_relaxed));
      run.u_V.push_back(slot.u_v.load(std::memory_order_relaxed));
      run.uc_V.push_back(slot.uc_v.load(std::memory_order_relaxed));
    }
    // The loop may have lapped the start while we copied: drop what it overwrote.
    const auto lapped = oldest() > first ? oldest() - first : 0;
    if (lapped > 0) {
      for (auto* c : {&run.t_s, &run.r_mm, &run.y_mm, &run.u_V, &run.uc_V})
        c->erase(c->begin(), c->begin() + static_cast<std::ptrdiff_t>(std::min<std::uint64_t>(lapped, c->size())));
      first += lapped;
    }
    return first;
  }

 private:
  struct Slot {
    std::atomic<double> t_s{0}, r_mm{0}, y_mm{0}, u_v{0}, uc_v{0};
  };
  std::size_t capacity_;
  std::unique_ptr<Slot[]> slots_;
  std::atomic<std::uint64_t> written_{0};
};

}  // namespace epa::runtime
