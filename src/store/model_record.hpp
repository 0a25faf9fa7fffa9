#pragma once
// A plant model as the store keeps it: the Hammerstein model (ARX + dead zone, Ts, sensor scale)
// and where it came from (the paper, or identified from which runs with which fit figures).
#include <cstdint>
#include <string>

#include "core/hammerstein_model.hpp"

namespace epa::store {

struct ModelRecord {
  std::int64_t id = 0;  // 0 until stored
  std::string name;
  std::int64_t created_ms = 0;
  std::string source;           // "paper eq 9-10", "identified from runs/a.csv, runs/b.csv"
  core::HammersteinModel model;
  std::string fit_json = "{}";  // fit figures (JSON object), as epa identify reports them
};

}  // namespace epa::store
