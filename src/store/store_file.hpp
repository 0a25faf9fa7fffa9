#pragma once
// Opening the appliance's database file, whatever state it is in:
// - missing (or empty): created, migrated and seeded with the given model and tuning set;
// - from an older epa: migrated, data kept;
// - from a newer epa: refused with a message, the file untouched;
// - damaged (not a database, failed integrity check): moved aside with a timestamp (never
//   deleted) and a new seeded one created; `moved_aside` says where the old one went, so the
//   appliance can start in STOP with a fault that says so.
#include <cstdint>
#include <string>

#include "core/result.hpp"
#include "store/database.hpp"
#include "store/model_record.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

struct StoreSeed {
  ModelRecord model;
  TuningSet tuning;  // its model_id is filled in when seeding
};

struct OpenedStore {
  Database db;
  bool created = false;      // a new file (or a new one after moving a damaged one aside)
  bool seeded = false;
  int migrated_from = 0;     // schema version found in the file
  std::string moved_aside;   // non-empty: the damaged file's new name
  std::string damage;        // what was wrong with it
};

core::Result<OpenedStore> open_store(const std::string& path, const StoreSeed& seed, std::int64_t now_ms);

// Seeds an empty database (no tuning sets) in one transaction: the model, the set, active.
core::Status seed_if_empty(Database& db, const StoreSeed& seed, std::int64_t now_ms, bool* seeded = nullptr);

// An existing database for the command line (`epa tuning`): never created, migrated when older,
// refused when newer or damaged.
core::Result<Database> open_existing_store(const std::string& path);

// "<path>.corrupt-20261121T101500Z"
std::string moved_aside_name(const std::string& path, std::int64_t now_ms);

}  // namespace epa::store
