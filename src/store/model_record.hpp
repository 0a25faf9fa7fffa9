#pragma once
// A plant model as the store keeps it: the Hammerstein model (ARX + dead zone, Ts, sensor scale),
// what else is known of the axis (epa identify's verdict, the drive range it was identified on,
// the stick-slip model and its spread: the model file's optional keys), and where it came from
// (the paper, or identified from which runs with which fit figures).
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "core/hammerstein_model.hpp"
#include "core/model_file.hpp"
#include "core/stick_slip_params.hpp"

namespace epa::store {

struct ModelRecord {
  std::int64_t id = 0;  // 0 until stored
  std::string name;
  std::int64_t created_ms = 0;
  std::string source;           // "paper eq 9-10", "identified from runs/a.csv, runs/b.csv"
  core::HammersteinModel model;
  std::string fit_json = "{}";  // fit figures (JSON object), as epa identify reports them
  // The model file's optional keys (core/model_file.hpp), kept in the axis_json column.
  core::AxisModel axis_model = core::AxisModel::kHammerstein;
  std::optional<std::array<double, 2>> identified_drive_v = std::nullopt;  // V: lowest, highest
  std::optional<core::StickSlipParams> stick_slip = std::nullopt;
  std::optional<core::StickSlipSpread> stick_slip_spread = std::nullopt;  // needs stick_slip
};

// The epa-model/1 view of a record, and the record of a model file (id and created_ms 0): the one
// place the two are converted, so a new key of the model file reaches the store whole.
core::ModelFile model_file_of(const ModelRecord& record);
ModelRecord model_record_of(const core::ModelFile& file, std::string name, std::string fit_json = "{}");

}  // namespace epa::store
