#include "appliance/store_save.hpp"

#include <cmath>

#include "store/audit_log.hpp"
#include "store/model_table.hpp"
#include "store/store_file.hpp"
#include "store/transaction.hpp"
#include "store/tuning_set_table.hpp"

namespace epa::appliance {

core::Result<std::int64_t> save_model(const std::string& db_path, store::ModelRecord model) {
  auto db = store::open_existing_store(db_path);
  if (!db) return db.error();
  auto tx = store::Transaction::begin(*db);
  if (!tx) return tx.error();
  model.created_ms = core::unix_time_ms();
  auto id = store::ModelTable(*db).find_or_insert(model);
  if (!id) return id.error();
  if (auto s = store::AuditLog(*db).append({core::unix_time_ms(), "cli", "save_model", std::nan(""), static_cast<double>(*id)}); !s) return s.error();
  if (auto s = tx->commit(); !s) return s.error();
  return id;
}

core::Result<std::int64_t> save_tuning_set(const std::string& db_path, store::ModelRecord model, store::TuningSet set,
                                           const std::string& source) {
  if (auto s = store::validate(set, model.model); !s) return s.error();
  auto db = store::open_existing_store(db_path);
  if (!db) return db.error();
  auto tx = store::Transaction::begin(*db);
  if (!tx) return tx.error();
  model.created_ms = set.created_ms = set.modified_ms = core::unix_time_ms();
  auto model_id = store::ModelTable(*db).find_or_insert(model);
  if (!model_id) return model_id.error();
  set.model_id = *model_id;
  auto id = store::TuningSetTable(*db).insert(set);
  if (!id) return id.error();
  if (auto s = store::AuditLog(*db).append({core::unix_time_ms(), source, "save_tuning_set", std::nan(""), static_cast<double>(*id)}); !s)
    return s.error();
  if (auto s = tx->commit(); !s) return s.error();
  return id;
}

}  // namespace epa::appliance
