#pragma once
// The runs the recorder wrote, for a thread that waits for one: the commissioning sequence waits
// for its excitation run here (the recorder's Written callback puts every run in).
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>

#include "core/run.hpp"

namespace epa::app {

class RecordedRuns {
 public:
  void put(const std::string& path, const core::Run& run) {
    {
      std::lock_guard lock(mutex_);
      ++count_;
      last_ = {path, run};
    }
    changed_.notify_all();
  }
  std::uint64_t count() const {
    std::lock_guard lock(mutex_);
    return count_;
  }
  // The first run written after `count()` was `seen`, waiting at most `timeout`.
  std::optional<core::Run> wait_after(std::uint64_t seen, std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    if (!changed_.wait_for(lock, timeout, [&] { return count_ > seen; })) return std::nullopt;
    return last_.second;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::uint64_t count_ = 0;
  std::pair<std::string, core::Run> last_;
};

}  // namespace epa::app
