#pragma once
// The run history: one row per recorded run file.
#include <vector>

#include "core/result.hpp"
#include "store/database.hpp"
#include "store/run_record.hpp"

namespace epa::store {

class RunTable {
 public:
  explicit RunTable(Database& db) : db_(db) {}

  core::Result<std::int64_t> insert(const RunRecord& run);
  core::Result<std::vector<RunRecord>> recent(std::size_t limit);  // newest first
  // Deletes the oldest rows beyond the newest `keep_rows`: the run files they name are rotated out
  // by the recorder's quota long before; the number deleted.
  core::Result<std::int64_t> drop_oldest(std::int64_t keep_rows);

 private:
  Database& db_;
};

}  // namespace epa::store
