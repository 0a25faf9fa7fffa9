#pragma once
// The tuning_sets table and which set is active. A set is found by id or by name; activation
// checks the set exists; `last good` is the set most recently loaded and validated by the
// appliance, the fall-back when the active one fails validation.
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "store/database.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

class TuningSetTable {
 public:
  explicit TuningSetTable(Database& db) : db_(db) {}

  core::Result<std::int64_t> insert(const TuningSet& set);  // duplicate names refused
  core::Result<TuningSet> get(std::int64_t id);
  core::Result<TuningSet> find(const std::string& id_or_name);  // "3" or "paper"
  core::Result<std::vector<TuningSet>> all();
  core::Status update(const TuningSet& set);  // every value column of set.id, and modified_ms

  core::Status activate(std::int64_t id);
  core::Result<std::optional<std::int64_t>> active_id();
  core::Status set_last_good(std::int64_t id);
  core::Result<std::optional<std::int64_t>> last_good_id();

 private:
  core::Status put_setting(const std::string& key, std::int64_t value);
  core::Result<std::optional<std::int64_t>> setting(const std::string& key);
  Database& db_;
};

}  // namespace epa::store
