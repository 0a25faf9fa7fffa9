#include "appliance/control_setup.hpp"

#include <set>
#include <vector>

#include "appliance/byte_sizes.hpp"
#include "appliance/tuning_source.hpp"
#include "core/format.hpp"
#include "points/position_records.hpp"
#include "store/tuning_set.hpp"

namespace epa::appliance {

namespace {

// The points whose accepted values the store keeps: the register map's persisted column (without
// Modbus, the setpoint), and always the position-record table, whichever interface edits it.
std::set<points::PointId> persisted_points(const std::optional<modbus::RegisterMap>& map) {
  std::set<points::PointId> out;
  if (!map) out.insert(points::PointId::kSetpoint);
  for (const auto& e : map ? map->entries() : std::vector<modbus::RegisterEntry>{})
    if (e.persisted) out.insert(e.point->id);
  for (std::size_t k = 0; k < points::kRecordPoints; ++k) out.insert(points::indexed_id(points::PointId::kRecordTarget0, k));
  return out;
}

// The store's seed on first start: the configuration's model and design ("paper" when both are
// the paper's).
core::Result<store::StoreSeed> seed_from_config(const config::ApplianceConfig& c, const core::ModelFile& plant_model) {
  auto polynomials = load_controller_polynomials(c.design_path);
  if (!polynomials) return polynomials.error();
  const bool paper = c.model_path.empty() && c.design_path.empty();
  return make_seed(paper ? "paper" : "initial", plant_model, *polynomials, c.runtime.controller, c.lc_mm, c.valve_limit_v);
}

// The loop's rules from the store's active set; its retained setpoint unless one was given.
void take_from_store(config::ApplianceConfig& c, StoreStartup& store, bool setpoint_given) {
  const core::HammersteinModel& model = store.model.model;  // its Ts is the loop's (load_active_tuning)
  c.runtime.mm_per_volt = model.mm_per_volt;
  c.runtime.controller = store.set.controller;
  c.runtime.start_fault = store.start_fault;
  if (store.retained_setpoint_mm && !setpoint_given) {
    const double r = *store.retained_setpoint_mm;
    if (r >= c.runtime.setpoint_min_mm && r <= c.runtime.setpoint_max_mm) c.runtime.start_setpoint_mm = r;
    else store.warnings.push_back("store: retained setpoint " + core::format_number(r) + " mm is outside the configured limits: not used");
  }
}

}  // namespace

core::Result<points::WriteLimits> write_limits(const config::ApplianceConfig& c, const std::string& config_path,
                                               const std::optional<modbus::RegisterMap>& map) {
  auto limits = points::WriteLimits::from_config(c.runtime, config_path);
  if (!limits) return limits.error();
  if (map)
    if (auto s = modbus::narrow_limits(*map, *limits); !s) return s.error();
  if (auto why = limits->check(points::PointId::kSetpoint, c.runtime.start_setpoint_mm); !why.empty())
    return core::invalid_argument("start-up setpoint: " + why);
  return limits;
}

core::Result<ControlSetup> prepare_control(config::ApplianceConfig& c, const std::optional<modbus::RegisterMap>& map, bool setpoint_given) {
  auto plant_model = load_model(c.model_path);
  if (!plant_model) return plant_model.error();
  // The paper does not print its Ts (docs/dev/decisions.md), so its model takes the loop's period; an
  // identified model is only valid at the Ts it was identified at.
  if (c.model_path.empty()) plant_model->model.Ts = c.runtime.period_s;
  auto seed = seed_from_config(c, *plant_model);
  if (!seed) return seed.error();
  auto store = open_tuning_store(c.store_path, *seed, persisted_points(map), c.runtime.period_s);
  if (!store) return store.error();
  store->writer->set_limits({.audit_max_rows = c.audit_max_rows, .min_free_bytes = mib_to_bytes(c.store_min_free_mb)});
  take_from_store(c, *store, setpoint_given);

  const control::ControllerConfig base =
      runtime::with_loop_limits(store::controller_config(store->set, store->model.model, c.runtime.safe_valve_v), c.runtime);
  auto tuning = runtime::make_tuning(base);
  if (!tuning) return tuning.error();  // cannot happen: load_active_tuning validated the set
  return ControlSetup{std::move(*plant_model), std::move(*store), base, *tuning};
}

}  // namespace epa::appliance
