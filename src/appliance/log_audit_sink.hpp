#pragma once
// The audit trail in the log as well (journald keeps it with the rest): one
// line per accepted change, with who, what, from and to (or an interface's
// event); then on to the next sink (the store). A write flood would log at
// request speed: the lines are throttled (core/log_throttle.hpp), the held-back
// ones counted in a summary line; the store still gets every change.
#include <spdlog/spdlog.h>

#include "core/audit.hpp"
#include "core/log_throttle.hpp"

namespace epa::appliance {

class LogAuditSink final : public core::AuditSink {
public:
  LogAuditSink(core::LogThrottle &throttle, core::AuditSink *next = nullptr)
      : throttle_(throttle), next_(next) {}
  void record(const std::vector<core::AuditEntry> &change) override {
    std::string summary;
    for (const auto &e : change) {
      const bool admitted = throttle_.admit("audit", summary);
      if (!summary.empty())
        spdlog::info("audit: {}", summary);
      if (admitted)
        spdlog::info("audit: {} {}", e.source, core::audit_text(e));
    }
    if (next_)
      next_->record(change);
  }
  core::ChangeCounters counters() const override {
    return next_ ? next_->counters() : core::ChangeCounters{};
  }

private:
  core::LogThrottle &throttle_;
  core::AuditSink *next_;
};

} // namespace epa::appliance
