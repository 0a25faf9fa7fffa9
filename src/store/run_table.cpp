#include "store/run_table.hpp"

#include "store/statement.hpp"

namespace epa::store {

core::Result<std::int64_t> RunTable::insert(const RunRecord& r) {
  auto stmt = db_.prepare(
      "INSERT INTO runs (path, recorded_ms, controller, tuning_set_id, samples, ts_s, from_mm, to_mm, rise_s, settling_s, "
      "ess_mm, overshoot_pct) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
  if (!stmt) return stmt.error();
  stmt->bind(1, r.path).bind(2, r.recorded_ms).bind(3, r.controller).bind(4, r.tuning_set_id).bind(5, r.samples).bind(6, r.Ts);
  stmt->bind(7, r.from_mm).bind(8, r.to_mm).bind(9, r.rise_s).bind(10, r.settling_s).bind(11, r.ess_mm).bind(12, r.overshoot_pct);
  if (auto s = stmt->run(); !s) return s.error();
  return db_.last_insert_id();
}

core::Result<std::int64_t> RunTable::drop_oldest(std::int64_t keep_rows) {
  auto stmt = db_.prepare("DELETE FROM runs WHERE id <= (SELECT max(id) FROM runs) - ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, keep_rows);
  if (auto s = stmt->run(); !s) return s.error();
  return db_.changes();
}

core::Result<std::vector<RunRecord>> RunTable::recent(std::size_t limit) {
  auto stmt = db_.prepare(
      "SELECT id, path, recorded_ms, controller, tuning_set_id, samples, ts_s, from_mm, to_mm, rise_s, settling_s, ess_mm, "
      "overshoot_pct FROM runs ORDER BY id DESC LIMIT ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, static_cast<std::int64_t>(limit));
  std::vector<RunRecord> out;
  auto s = stmt->each_row([&out](const Statement& row) {
    RunRecord r;
    r.id = row.column_int(0);
    r.path = row.column_text(1);
    r.recorded_ms = row.column_int(2);
    r.controller = row.column_text(3);
    if (!row.column_is_null(4)) r.tuning_set_id = row.column_int(4);
    r.samples = row.column_int(5);
    r.Ts = row.column_double(6);
    r.from_mm = row.column_optional_double(7);
    r.to_mm = row.column_optional_double(8);
    r.rise_s = row.column_optional_double(9);
    r.settling_s = row.column_optional_double(10);
    r.ess_mm = row.column_optional_double(11);
    r.overshoot_pct = row.column_optional_double(12);
    out.push_back(std::move(r));
    return core::ok();
  });
  if (!s) return s.error();
  return out;
}

}  // namespace epa::store
