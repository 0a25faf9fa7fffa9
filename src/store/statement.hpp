#pragma once
// A prepared SQLite statement (RAII): bind by 1-based index, step through rows, read columns by
// 0-based index. step() returns true while a row is available and an error naming the SQL
// when SQLite fails (disk full, read-only, corrupt), never silently false.
#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>

#include "core/result.hpp"

namespace epa::store {

class Database;

class Statement {
 public:
  Statement(sqlite3_stmt* stmt, Database* db) : stmt_(stmt), db_(db) {}
  Statement(Statement&& other) noexcept : stmt_(other.stmt_), db_(other.db_) { other.stmt_ = nullptr; }
  Statement& operator=(Statement&&) = delete;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement() { sqlite3_finalize(stmt_); }

  Statement& bind(int index, double value);
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, static_cast<std::int64_t>(value)); }
  Statement& bind(int index, const std::string& value);
  Statement& bind(int index, const char* value) { return bind(index, std::string(value)); }
  Statement& bind(int index, const std::optional<std::int64_t>& value);
  Statement& bind(int index, const std::optional<double>& value);
  Statement& bind_real_or_null(int index, double value);  // NaN/inf: NULL (SQLite has no NaN)
  Statement& bind_null(int index);

  core::Result<bool> step();  // true: a row is ready to read

  // Steps through every row, calling visit(*this) (which returns a core::Status) for each; stops
  // at the first error, SQLite's or visit's.
  template <typename Visit>
  core::Status each_row(Visit&& visit) {
    for (;;) {
      auto row = step();
      if (!row) return row.error();
      if (!*row) return core::ok();
      if (core::Status s = visit(*this); !s) return s;
    }
  }
  core::Status run();         // steps a statement that returns no rows
  void reset();

  double column_double(int index) const;
  std::int64_t column_int(int index) const;
  std::string column_text(int index) const;
  bool column_is_null(int index) const;
  std::optional<double> column_optional_double(int index) const;
  double column_double_or_nan(int index) const;

 private:
  sqlite3_stmt* stmt_;
  Database* db_;
};

}  // namespace epa::store
