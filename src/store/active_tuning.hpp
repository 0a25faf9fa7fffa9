#pragma once
// The tuning the appliance starts with: the active set, validated with its model. A set that
// fails validation is refused with a message and the last good one is used instead (then any
// other set that validates, newest first); the set that is finally used becomes `last good`.
#include <optional>
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

// Errors only when no set at all validates (or the database fails). With `loop_period_s`, a set
// whose model was identified at another Ts is refused like an invalid one (an imported set at
// 10 ms had stopped the appliance from starting while good sets were there).
core::Result<LoadedTuning> load_active_tuning(Database& db, std::optional<double> loop_period_s = std::nullopt);

}  // namespace epa::store
