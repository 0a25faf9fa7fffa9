#include "store/audit_log.hpp"

#include "store/statement.hpp"

#include <algorithm>

namespace epa::store {

core::Status AuditLog::append(const core::AuditEntry& e) {
  auto stmt = db_.prepare("INSERT INTO audit_log (time_ms, source, point, old_value, new_value) VALUES (?, ?, ?, ?, ?)");
  if (!stmt) return stmt.error();
  stmt->bind(1, e.unix_time_ms).bind(2, e.source).bind(3, e.point).bind_real_or_null(4, e.old_value).bind_real_or_null(5, e.new_value);
  return stmt->run();
}

core::Result<std::vector<AuditRecord>> AuditLog::query(const AuditFilter& f) {
  // Fixed SQL with optional conditions: every filter is a bound parameter, never spliced text.
  auto stmt = db_.prepare(
      "SELECT id, time_ms, source, point, old_value, new_value FROM audit_log "
      "WHERE (?1 IS NULL OR time_ms >= ?1) AND (?2 IS NULL OR time_ms <= ?2) "
      "AND (?3 = '' OR instr(source, ?3) > 0) AND (?4 = '' OR point = ?4) "
      "ORDER BY id DESC LIMIT ?5");
  if (!stmt) return stmt.error();
  stmt->bind(1, f.since_ms).bind(2, f.until_ms).bind(3, f.source).bind(4, f.point);
  stmt->bind(5, f.limit == 0 ? std::int64_t{-1} : static_cast<std::int64_t>(f.limit));
  std::vector<AuditRecord> out;
  auto s = stmt->each_row([&out](const Statement& row) {
    out.push_back({row.column_int(0),
                   {row.column_int(1), row.column_text(2), row.column_text(3), row.column_double_or_nan(4),
                    row.column_double_or_nan(5)}});
    return core::ok();
  });
  if (!s) return s.error();
  return out;
}

core::Result<std::int64_t> AuditLog::drop_oldest(std::int64_t keep_rows) {
  auto stmt = db_.prepare("DELETE FROM audit_log WHERE id <= (SELECT max(id) FROM audit_log) - ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, std::max(keep_rows, core::kAuditMinRows));
  if (auto s = stmt->run(); !s) return s.error();
  return db_.changes();
}

core::Result<std::int64_t> AuditLog::count() {
  auto stmt = db_.prepare("SELECT count(*) FROM audit_log");
  if (!stmt) return stmt.error();
  auto row = stmt->step();
  if (!row) return row.error();
  return stmt->column_int(0);
}

}  // namespace epa::store
