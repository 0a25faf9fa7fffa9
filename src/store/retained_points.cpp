#include "store/retained_points.hpp"

#include "store/statement.hpp"

namespace epa::store {

core::Status RetainedPoints::put(const std::string& point, double value, std::int64_t changed_ms) {
  auto stmt = db_.prepare(
      "INSERT INTO retained_points (point, value, changed_ms) VALUES (?, ?, ?) "
      "ON CONFLICT(point) DO UPDATE SET value = excluded.value, changed_ms = excluded.changed_ms");
  if (!stmt) return stmt.error();
  stmt->bind(1, point).bind(2, value).bind(3, changed_ms);
  return stmt->run();
}

core::Result<std::map<std::string, double>> RetainedPoints::all() {
  auto stmt = db_.prepare("SELECT point, value FROM retained_points");
  if (!stmt) return stmt.error();
  std::map<std::string, double> out;
  auto s = stmt->each_row([&out](const Statement& row) {
    out[row.column_text(0)] = row.column_double(1);
    return core::ok();
  });
  if (!s) return s.error();
  return out;
}

}  // namespace epa::store
