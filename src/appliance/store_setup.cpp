#include "appliance/store_setup.hpp"

#include <spdlog/spdlog.h>


#include "points/point_catalog.hpp"
#include "store/active_tuning.hpp"
#include "store/fault_table.hpp"
#include "store/retained_points.hpp"
#include "store/schema.hpp"

namespace epa::appliance {

store::StoreSeed make_seed(const std::string& name, const core::ModelFile& model, const ControllerPolynomials& polynomials,
                           control::ControllerKind controller, double lc_mm, double valve_limit_v) {
  store::StoreSeed seed;
  seed.model = store::model_record_of(model, name);  // with the file's stick-slip model, its spread and verdict
  if (seed.model.source.empty()) seed.model.source = "the configuration's model";
  seed.tuning.name = name;
  seed.tuning.source = "seeded from the configuration: " + polynomials.source;
  seed.tuning.controller = controller;
  seed.tuning.F = polynomials.F;
  seed.tuning.G = polynomials.G;
  seed.tuning.H = polynomials.H;
  seed.tuning.dead_zone = model.model.dead_zone;
  seed.tuning.lc_mm = lc_mm;
  seed.tuning.valve_limit_v = valve_limit_v;
  return seed;
}

core::Result<StoreStartup> open_tuning_store(const std::string& path, const store::StoreSeed& seed,
                                             std::set<points::PointId> persisted_points, double loop_period_s) {
  auto opened = store::open_store(path, seed, core::unix_time_ms());
  if (!opened) return core::Error{opened.error().code, "store: " + opened.error().message};
  StoreStartup out;
  if (!opened->moved_aside.empty()) {
    out.start_fault = runtime::FaultCode::kStoreDamaged;
    out.warnings.push_back("store: " + path + " was damaged (" + opened->damage + "): moved aside to " + opened->moved_aside +
                           "; a new one was seeded from the configuration; starting in FAULT until reset");
  } else if (opened->created) {
    out.notes.push_back("store: created " + path + " and seeded it from the configuration");
  } else if (opened->migrated_from != store::kSchemaVersion) {
    out.notes.push_back("store: migrated " + path + " from schema version " + std::to_string(opened->migrated_from) +
                           " to " + std::to_string(store::kSchemaVersion));
  }
  auto loaded = store::load_active_tuning(opened->db, loop_period_s);
  if (!loaded) return core::Error{loaded.error().code, "store: " + loaded.error().message};
  for (const auto& refusal : loaded->refused) out.warnings.push_back("store: refused " + refusal + "; using the next good set");
  auto retained = store::RetainedPoints(opened->db).all();
  if (!retained) return core::Error{retained.error().code, "store: " + retained.error().message};
  if (auto it = retained->find(std::string(points::name(points::PointId::kSetpoint))); it != retained->end()) out.retained_setpoint_mm = it->second;
  for (std::size_t k = 0; k < points::kRecordPoints; ++k) {
    const points::PointId id = points::indexed_id(points::PointId::kRecordTarget0, k);
    points::RecordField f;
    points::record_field(id, f);
    if (auto it = retained->find(std::string(points::name(id))); it != retained->end())
      points::set_record_value(out.records[f.record], f.kind, it->second);
  }
  store::FaultTable faults(opened->db);
  auto history = faults.recent(runtime::kFaultHistoryEntries);
  if (!history) return core::Error{history.error().code, "store: " + history.error().message};
  auto count = faults.count();
  if (!count) return core::Error{count.error().code, "store: " + count.error().message};
  out.faults = std::move(*history);
  out.fault_count = *count;

  out.set = loaded->set;
  out.model = loaded->model;
  out.notes.push_back("store: tuning set '" + out.set.name + "' (id " + std::to_string(out.set.id) + ", model '" +
                         out.model.name + "') from " + path);
  out.writer = std::make_unique<store::StoreWriter>(std::move(opened->db), out.set, std::move(persisted_points),
                                                    [](const std::string& line) { spdlog::warn("{}", line); });
  return out;
}

}  // namespace epa::appliance
