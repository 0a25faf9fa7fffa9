#pragma once
// The models table: insert and read plant models.
#include <vector>

#include "core/result.hpp"
#include "store/database.hpp"
#include "store/model_record.hpp"

namespace epa::store {

class ModelTable {
 public:
  explicit ModelTable(Database& db) : db_(db) {}

  // Validates the model first; a duplicate name is refused with the name in the message.
  core::Result<std::int64_t> insert(const ModelRecord& record);
  // The id of a stored model with the same dynamics (A, B, dead zone, Ts, scale, and the axis_json
  // fields: the verdict, drive range, stick-slip model and spread), or of `record` inserted under
  // its name (with " #2", " #3" ... when the name is taken by another model).
  core::Result<std::int64_t> find_or_insert(ModelRecord record);
  core::Result<ModelRecord> get(std::int64_t id);
  core::Result<std::vector<ModelRecord>> all();

 private:
  Database& db_;
};

}  // namespace epa::store
