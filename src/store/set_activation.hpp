#pragma once
// Finding a tuning set with its model, and making a set the active one (what the appliance loads
// at its next start) with the switch in the audit trail. `epa tuning` and the commissioning
// sequence both do this; inside the caller's transaction.
#include <cstdint>
#include <string>

#include "core/result.hpp"
#include "store/active_tuning.hpp"
#include "store/database.hpp"

namespace epa::store {

// By id ("3") or name; `refused` stays empty.
core::Result<LoadedTuning> find_set_with_model(Database& db, const std::string& id_or_name);

// Activates set `id` and audits "active_tuning_set" old id -> new id with `source`.
core::Status activate_audited(Database& db, std::int64_t id, const std::string& source);

}  // namespace epa::store
