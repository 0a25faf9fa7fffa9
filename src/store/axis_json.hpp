#pragma once
// The models table's axis_json column: what a model record knows of the axis beyond the
// Hammerstein model, as a JSON object with the model file's keys and field names:
//   {"axis_model": "stick-slip", "identified_drive_v": [-3.0, 3.0],
//    "stick_slip": {"break_right_v": 1.17, ..., "delay_samples": 2},
//    "stick_slip_spread": {"friction_log_ratio": 0.33, ...}}
// Every key is optional; '{}' (models stored before schema 6) is nothing known: the Hammerstein
// model describes the axis. A table read wants it whole and valid, as the model file's reader does.
#include <string>

#include "core/result.hpp"
#include "store/model_record.hpp"

namespace epa::store {

// The record's axis_model, identified_drive_v, stick_slip and stick_slip_spread (those it has).
std::string axis_json_text(const ModelRecord& record);

// Sets those four fields of `record` from `text`. Errors name `what` (the model), the column and
// the field: an unknown key, a missing or wrong field, a rule of the model file broken.
core::Status read_axis_json(const std::string& text, const std::string& what, ModelRecord& record);

// The model file's rules on the four fields (each value valid, the spread and a stick-slip
// verdict need a stick-slip model); the message names the field.
core::Status check_axis_fields(const ModelRecord& record);

}  // namespace epa::store
