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

 private:
  Database& db_;
};

}  // namespace epa::store
