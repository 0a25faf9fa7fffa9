#pragma once
// The runs the recorder wrote, for a thread that waits for one: the commissioning sequence waits
// for its excitation run here (the recorder's Written callback puts every run in). Other runs
// arrive meanwhile (a move's file when RUN ends), so a waiter says which run it wants.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "core/run.hpp"

namespace epa::appliance {

class RecordedRuns {
 public:
  void put(const std::string& path, const core::Run& run) {
    {
      std::lock_guard lock(mutex_);
      ++count_;
      recent_.push_back({count_, path, run});
      if (recent_.size() > kKept) recent_.pop_front();
    }
    changed_.notify_all();
  }
  std::uint64_t count() const {
    std::lock_guard lock(mutex_);
    return count_;
  }
  // The first run written after `count()` was `seen` that `wanted` accepts, waiting at most `timeout`.
  std::optional<core::Run> wait_for(std::uint64_t seen, const std::function<bool(const core::Run&)>& wanted,
                                    std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    std::optional<core::Run> found;
    changed_.wait_for(lock, timeout, [&] {
      for (const auto& r : recent_)
        if (r.number > seen && wanted(r.run)) return found = r.run, true;
      return false;
    });
    return found;
  }

 private:
  static constexpr std::size_t kKept = 16;  // runs written while one waits: a move's, a request's
  struct Entry {
    std::uint64_t number;
    std::string path;
    core::Run run;
  };
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::uint64_t count_ = 0;
  std::deque<Entry> recent_;
};

}  // namespace epa::appliance
