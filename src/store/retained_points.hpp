#pragma once
// Retained values of persisted points that are not part of a tuning set (the setpoint): like a
// PLC's retentive memory, restored at the next start.
#include <map>
#include <string>

#include "core/result.hpp"
#include "store/database.hpp"

namespace epa::store {

class RetainedPoints {
 public:
  explicit RetainedPoints(Database& db) : db_(db) {}

  core::Status put(const std::string& point, double value, std::int64_t changed_ms);
  core::Result<std::map<std::string, double>> all();

 private:
  Database& db_;
};

}  // namespace epa::store
