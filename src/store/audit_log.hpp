#pragma once
// The audit log: append-only (triggers refuse UPDATE and DELETE), read back with filters.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/audit.hpp"
#include "core/result.hpp"
#include "store/database.hpp"

namespace epa::store {

struct AuditFilter {
  std::optional<std::int64_t> since_ms, until_ms;  // inclusive, unix ms
  std::string source;                               // substring of the source ("modbus", "10.0.0.5"); "" any
  std::string point;                                // exact point name; "" any
  std::size_t limit = 100;                          // newest first; 0: all
};

struct AuditRecord {
  std::int64_t id = 0;
  core::AuditEntry entry;
};

class AuditLog {
 public:
  explicit AuditLog(Database& db) : db_(db) {}

  core::Status append(const core::AuditEntry& entry);
  core::Result<std::vector<AuditRecord>> query(const AuditFilter& filter);  // newest first
  core::Result<std::int64_t> count();
  // Deletes the oldest rows beyond the newest `keep_rows` (at least core::kAuditMinRows); the
  // number deleted.
  core::Result<std::int64_t> drop_oldest(std::int64_t keep_rows);

 private:
  Database& db_;
};

}  // namespace epa::store
