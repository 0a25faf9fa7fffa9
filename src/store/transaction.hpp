#pragma once
// A write transaction (RAII): BEGIN IMMEDIATE on construction (takes the write lock up front, so
// a busy database fails here, not halfway through), ROLLBACK on destruction unless committed.
// Nothing is ever half-applied.
#include "core/result.hpp"
#include "store/database.hpp"

namespace epa::store {

class Transaction {
 public:
  static core::Result<Transaction> begin(Database& db);
  Transaction(Transaction&& other) noexcept : db_(other.db_), open_(other.open_) { other.open_ = false; }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  Transaction& operator=(Transaction&&) = delete;
  ~Transaction();

  core::Status commit();

 private:
  explicit Transaction(Database& db) : db_(&db), open_(true) {}
  Database* db_;
  bool open_;
};

}  // namespace epa::store
