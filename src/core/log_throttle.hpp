#pragma once
// Repeated log lines, bounded. A client can make the appliance log at request
// speed (a write flood audits every write, a reconnecting crowd is evicted
// again and again), which would fill the disk and bury the real events. Each
// kind of line gets `lines_per_window` lines per window; the rest are counted,
// and the first line of the next window says how many there were: "412 more
// 'audit' lines in the last 60 s (not logged: at most 20 a window)".
// Thread-safe: I/O threads log through one instance.
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace epa::core {

class LogThrottle {
public:
  using Clock =
      std::function<std::int64_t()>; // monotonic ns; tests give their own
  LogThrottle(int lines_per_window, double window_s, Clock now_ns = steady_ns)
      : lines_per_window_(lines_per_window),
        window_ns_(static_cast<std::int64_t>(window_s * 1e9)),
        now_ns_(std::move(now_ns)) {}

  // Whether a line of `kind` may be logged now; `summary` gets the line that
  // reports the lines held back in the window that ended (empty when there were
  // none), to log first.
  bool admit(const std::string &kind, std::string &summary) {
    std::lock_guard lock(mutex_);
    const std::int64_t now = now_ns_();
    Window &w = windows_[kind];
    summary.clear();
    if (now - w.start_ns >= window_ns_) {
      if (w.held_back > 0)
        summary = summary_text(kind, w, now);
      w = {now, 0, 0};
    }
    if (w.logged < lines_per_window_) {
      ++w.logged;
      return true;
    }
    ++w.held_back;
    return false;
  }

  // The summaries of windows that have ended with lines held back, for a
  // periodic caller (a flood that stops is still reported); each window is
  // reported once.
  std::vector<std::string> due_summaries() {
    std::lock_guard lock(mutex_);
    const std::int64_t now = now_ns_();
    std::vector<std::string> out;
    for (auto &[kind, w] : windows_)
      if (w.held_back > 0 && now - w.start_ns >= window_ns_) {
        out.push_back(summary_text(kind, w, now));
        w = {now, 0, 0};
      }
    return out;
  }

  static std::int64_t steady_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

private:
  struct Window {
    std::int64_t start_ns = std::numeric_limits<std::int64_t>::min() / 2;
    int logged = 0;
    std::uint64_t held_back = 0;
  };
  std::string summary_text(const std::string &kind, const Window &w,
                           std::int64_t now) const {
    return std::to_string(w.held_back) + " more '" + kind +
           "' lines in the last " +
           std::to_string((now - w.start_ns) / 1'000'000'000) +
           " s (not logged: at most " + std::to_string(lines_per_window_) +
           " a window)";
  }
  const int lines_per_window_;
  const std::int64_t window_ns_;
  Clock now_ns_;
  std::mutex mutex_;
  std::map<std::string, Window>
      windows_; // few kinds, fixed by the code (never a client's text)
};

} // namespace epa::core
