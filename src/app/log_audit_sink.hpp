#pragma once
// The audit trail in the log as well (journald keeps it with the rest): one line per accepted
// change, with who, what, from and to (or an interface's event); then on to the next sink (the store).
#include <spdlog/spdlog.h>

#include "core/audit.hpp"

namespace epa::app {

class LogAuditSink final : public core::AuditSink {
 public:
  explicit LogAuditSink(core::AuditSink* next = nullptr) : next_(next) {}
  void record(const std::vector<core::AuditEntry>& change) override {
    for (const auto& e : change) spdlog::info("audit: {} {}", e.source, core::audit_text(e));
    if (next_) next_->record(change);
  }
  core::ChangeCounters counters() const override { return next_ ? next_->counters() : core::ChangeCounters{}; }

 private:
  core::AuditSink* next_;
};

}  // namespace epa::app
