#pragma once
// The audit trail in the log, until the SQLite store (issue 6) keeps it: one line per accepted
// change, with who, what, from and to.
#include <spdlog/spdlog.h>

#include "core/audit.hpp"

namespace epa::app {

class LogAuditSink final : public core::AuditSink {
 public:
  void record(const core::AuditEntry& e) override {
    spdlog::info("audit: {} set {} from {} to {}", e.source, e.point, e.old_value, e.new_value);
  }
};

}  // namespace epa::app
