#include "store/transaction.hpp"

namespace epa::store {

core::Result<Transaction> Transaction::begin(Database& db) {
  if (auto s = db.exec("BEGIN IMMEDIATE"); !s) return s.error();
  return Transaction(db);
}

Transaction::~Transaction() {
  if (open_) (void)db_->exec("ROLLBACK");
}

core::Status Transaction::commit() {
  auto s = db_->exec("COMMIT");
  if (s) {
    open_ = false;
    return s;
  }
  // A failed COMMIT (disk full, I/O error) may leave the transaction open: roll it back here.
  return s;
}

}  // namespace epa::store
