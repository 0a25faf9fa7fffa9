#pragma once
// What `epa serve` takes from the tuning store at start: the database opened whatever state it
// was in (created and seeded from the configuration's model and design on first start; moved
// aside and replaced when damaged; refused when newer), the active tuning set loaded and
// validated (a refused set falls back to the last good one), the retained setpoint, the fault
// history, and the store thread that keeps every accepted change from then on.
#include "points/position_records.hpp"
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "appliance/tuning_source.hpp"
#include "core/model_file.hpp"
#include "runtime/fault_history.hpp"
#include "runtime/mode.hpp"
#include "store/model_record.hpp"
#include "store/store_file.hpp"
#include "store/store_writer.hpp"
#include "store/tuning_set.hpp"

namespace epa::appliance {

struct StoreStartup {
  std::unique_ptr<store::StoreWriter> writer;
  store::TuningSet set;
  store::ModelRecord model;
  std::optional<double> retained_setpoint_mm;
  points::PositionRecords records;  // the position-record table as retained (defaults where none was)
  runtime::FaultCode start_fault = runtime::FaultCode::kNone;  // kStoreDamaged when moved aside
  std::vector<runtime::FaultRecord> faults;  // the fault history, newest first
  std::uint64_t fault_count = 0;             // faults recorded since the store was created
  std::vector<std::string> notes;     // for the log: what happened at start
  std::vector<std::string> warnings;  // ... and what an operator must look at
};

// The seed of a new database: the configuration's model and controller polynomials, named
// `name` ("paper" when they are the paper's).
store::StoreSeed make_seed(const std::string& name, const core::ModelFile& model, const ControllerPolynomials& polynomials,
                           control::ControllerKind controller, double lc_mm, double valve_limit_v);

// Errors: a database from a newer epa, a file that cannot be created, no valid tuning set.
core::Result<StoreStartup> open_tuning_store(const std::string& path, const store::StoreSeed& seed,
                                             std::set<points::PointId> persisted_points, double loop_period_s);

}  // namespace epa::appliance
