#include "store/set_activation.hpp"

#include <cmath>

#include "store/audit_log.hpp"
#include "store/model_table.hpp"
#include "store/tuning_set_table.hpp"

namespace epa::store {

core::Result<LoadedTuning> find_set_with_model(Database& db, const std::string& key) {
  auto set = TuningSetTable(db).find(key);
  if (!set) return set.error();
  auto model = ModelTable(db).get(set->model_id);
  if (!model) return model.error();
  return LoadedTuning{std::move(*set), std::move(*model), {}};
}

core::Status activate_audited(Database& db, std::int64_t id, const std::string& source) {
  TuningSetTable sets(db);
  auto before = sets.active_id();
  if (!before) return before.error();
  if (auto st = sets.activate(id); !st) return st;
  const double old_id = *before ? static_cast<double>(**before) : std::nan("");
  return AuditLog(db).append({core::unix_time_ms(), source, "active_tuning_set", old_id, static_cast<double>(id)});
}

}  // namespace epa::store
