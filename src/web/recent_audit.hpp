#pragma once
// An AuditSink decorator: keeps the last entries for the status page and forwards every entry to
// the next sink (the log, later the store). Modbus and web threads record through it at once.
#include <deque>
#include <mutex>
#include <vector>

#include "core/audit.hpp"

namespace epa::web {

class RecentAudit final : public core::AuditSink {
 public:
  explicit RecentAudit(core::AuditSink* next = nullptr, std::size_t capacity = 100) : next_(next), capacity_(capacity) {}

  void record(const std::vector<core::AuditEntry>& change) override {
    {
      std::lock_guard lock(mutex_);
      entries_.insert(entries_.end(), change.begin(), change.end());
      while (entries_.size() > capacity_) entries_.pop_front();
    }
    if (next_) next_->record(change);
  }
  core::ChangeCounters counters() const override { return next_ ? next_->counters() : core::ChangeCounters{}; }

  // Oldest first.
  std::vector<core::AuditEntry> entries() const {
    std::lock_guard lock(mutex_);
    return {entries_.begin(), entries_.end()};
  }

 private:
  core::AuditSink* next_;
  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::deque<core::AuditEntry> entries_;
};

}  // namespace epa::web
