#include "store/statement.hpp"

#include "store/database.hpp"

#include <cmath>
#include <limits>

namespace epa::store {

Statement& Statement::bind(int index, double value) { sqlite3_bind_double(stmt_, index, value); return *this; }
Statement& Statement::bind(int index, std::int64_t value) { sqlite3_bind_int64(stmt_, index, value); return *this; }
Statement& Statement::bind(int index, const std::string& value) {
  sqlite3_bind_text(stmt_, index, value.data(), static_cast<int>(value.size()), SQLITE_TRANSIENT);
  return *this;
}
Statement& Statement::bind(int index, const std::optional<std::int64_t>& value) {
  return value ? bind(index, *value) : bind_null(index);
}
Statement& Statement::bind(int index, const std::optional<double>& value) {
  return value ? bind_real_or_null(index, *value) : bind_null(index);
}
Statement& Statement::bind_real_or_null(int index, double value) {
  return std::isfinite(value) ? bind(index, value) : bind_null(index);
}
Statement& Statement::bind_null(int index) { sqlite3_bind_null(stmt_, index); return *this; }

core::Result<bool> Statement::step() {
  const int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const char* sql = sqlite3_sql(stmt_);
  return db_->error(std::string("'") + (sql ? sql : "?") + "' failed");
}

core::Status Statement::run() {
  auto r = step();
  if (!r) return r.error();
  reset();
  return core::ok();
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

double Statement::column_double(int index) const { return sqlite3_column_double(stmt_, index); }
std::int64_t Statement::column_int(int index) const { return sqlite3_column_int64(stmt_, index); }
std::string Statement::column_text(int index) const {
  const auto* text = sqlite3_column_text(stmt_, index);
  return text ? std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(sqlite3_column_bytes(stmt_, index)))
              : std::string();
}
bool Statement::column_is_null(int index) const { return sqlite3_column_type(stmt_, index) == SQLITE_NULL; }
std::optional<double> Statement::column_optional_double(int index) const {
  if (column_is_null(index)) return std::nullopt;
  return column_double(index);
}
double Statement::column_double_or_nan(int index) const {
  return column_is_null(index) ? std::numeric_limits<double>::quiet_NaN() : column_double(index);
}

}  // namespace epa::store
