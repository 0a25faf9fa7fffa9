#pragma once
// One SQLite connection (RAII). Errors carry SQLite's own message and extended result code, so a
// full disk, a read-only file or a damaged database can be told apart by the caller.
#include <sqlite3.h>

#include <cstdint>
#include <string>

#include "core/result.hpp"

namespace epa::store {

class Statement;

class Database {
 public:
  // Opens (creating when `create`) the file at `path`; ":memory:" gives a private in-memory
  // database. Sets a busy timeout so a second process (the `epa tuning` command) waits briefly.
  static core::Result<Database> open(const std::string& path, bool create);

  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;
  ~Database();

  core::Status exec(const std::string& sql);        // one or more statements without results
  core::Result<Statement> prepare(const std::string& sql);
  std::int64_t last_insert_id() const;
  int changes() const;                              // rows changed by the last statement
  const std::string& path() const { return path_; }

  // "<what>: <SQLite's message> (code N)"; the code is SQLite's extended result code.
  core::Error error(const std::string& what) const;
  int last_error_code() const;

  sqlite3* handle() const { return db_; }

 private:
  Database(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
  sqlite3* db_ = nullptr;
  std::string path_;
};

}  // namespace epa::store
