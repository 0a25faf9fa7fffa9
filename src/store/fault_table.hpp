#pragma once
// The fault history in the store: one row per fault the loop latched, the newest
// runtime::kFaultHistoryEntries kept. Written by the store thread (StoreWriter::record_fault),
// read at start and by `epa faults`.
#include <cstdint>
#include <vector>

#include "core/result.hpp"
#include "runtime/fault_history.hpp"
#include "store/database.hpp"

namespace epa::store {

class FaultTable {
 public:
  explicit FaultTable(Database& db) : db_(db) {}

  // Inserts `fault` and deletes all but the newest kFaultHistoryEntries rows. Call it inside a
  // transaction (the store writer's batch), so the insert and the trim are one change.
  core::Status add(const runtime::FaultRecord& fault);
  core::Result<std::vector<runtime::FaultRecord>> recent(std::size_t limit);  // newest first
  // Faults recorded since the store was created: AUTOINCREMENT's counter, which trimming leaves.
  core::Result<std::uint64_t> count();

 private:
  Database& db_;
};

}  // namespace epa::store
