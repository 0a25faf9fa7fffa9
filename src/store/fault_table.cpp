#include "store/fault_table.hpp"

#include "store/statement.hpp"

namespace epa::store {

core::Status FaultTable::add(const runtime::FaultRecord& f) {
  auto insert = db_.prepare(
      "INSERT INTO fault_history (time_ms, code, name, text, mode, position_mm, setpoint_mm, valve_v, sensor_v) "
      "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)");
  if (!insert) return insert.error();
  insert->bind(1, f.time_ms).bind(2, static_cast<int>(f.code)).bind(3, f.name).bind(4, f.text).bind(5, static_cast<int>(f.mode));
  insert->bind_real_or_null(6, f.position_mm).bind_real_or_null(7, f.setpoint_mm).bind_real_or_null(8, f.valve_v);
  insert->bind_real_or_null(9, f.sensor_v);
  if (auto s = insert->run(); !s) return s;
  auto trim = db_.prepare("DELETE FROM fault_history WHERE id NOT IN (SELECT id FROM fault_history ORDER BY id DESC LIMIT ?)");
  if (!trim) return trim.error();
  trim->bind(1, static_cast<std::int64_t>(runtime::kFaultHistoryEntries));
  return trim->run();
}

core::Result<std::vector<runtime::FaultRecord>> FaultTable::recent(std::size_t limit) {
  auto stmt = db_.prepare(
      "SELECT time_ms, code, name, text, mode, position_mm, setpoint_mm, valve_v, sensor_v FROM fault_history "
      "ORDER BY id DESC LIMIT ?");
  if (!stmt) return stmt.error();
  stmt->bind(1, static_cast<std::int64_t>(limit));
  std::vector<runtime::FaultRecord> out;
  auto s = stmt->each_row([&out](const Statement& row) {
    runtime::FaultRecord f;
    f.time_ms = row.column_int(0);
    f.code = static_cast<runtime::FaultCode>(row.column_int(1));
    f.name = row.column_text(2);
    f.text = row.column_text(3);
    f.mode = static_cast<runtime::Mode>(row.column_int(4));
    f.position_mm = row.column_double_or_nan(5);
    f.setpoint_mm = row.column_double_or_nan(6);
    f.valve_v = row.column_double_or_nan(7);
    f.sensor_v = row.column_double_or_nan(8);
    out.push_back(std::move(f));
    return core::ok();
  });
  if (!s) return s.error();
  return out;
}

core::Result<std::uint64_t> FaultTable::count() {
  auto stmt = db_.prepare("SELECT COALESCE((SELECT seq FROM sqlite_sequence WHERE name = 'fault_history'), 0)");
  if (!stmt) return stmt.error();
  auto row = stmt->step();
  if (!row) return row.error();
  return static_cast<std::uint64_t>(stmt->column_int(0));
}

}  // namespace epa::store
