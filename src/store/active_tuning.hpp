#pragma once
// The tuning the appliance starts with: the active set, validated with its model. A set that
// fails validation is refused with a message and the last good one is used instead (then any
// other set that validates, newest first); the set that is finally used becomes `last good`.
#include <string>
#include <vector>

#include "core/result.hpp"
#include "store/database.hpp"
#include "store/model_record.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

struct LoadedTuning {
  TuningSet set;
  ModelRecord model;
  std::vector<std::string> refused;  // one message per set that failed validation
};

// Errors only when no set at all validates (or the database fails).
core::Result<LoadedTuning> load_active_tuning(Database& db);

}  // namespace epa::store
