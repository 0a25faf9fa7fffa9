#pragma once
// `epa identify --save` and `epa design --save`: what they produce, into an existing tuning store
// (the appliance's database), in one transaction each, audited with source "cli".
#include <cstdint>
#include <string>

#include "core/result.hpp"
#include "store/model_record.hpp"
#include "store/tuning_set.hpp"

namespace epa::appliance {

// The model, reusing a stored model with the same dynamics. Returns its id.
core::Result<std::int64_t> save_model(const std::string& db_path, store::ModelRecord model);

// The set with its model (reused when already stored). Returns the set's id. The set is not
// activated: `epa tuning activate` does that, after a look at `epa tuning diff`.
// `source` goes into the audit trail ("cli", or the commissioning's requester).
core::Result<std::int64_t> save_tuning_set(const std::string& db_path, store::ModelRecord model, store::TuningSet set,
                                           const std::string& source = "cli");

}  // namespace epa::appliance
