#pragma once
// Tuning files (TOML, `epa-tuning/1`): one tuning set with its model embedded, so a file stands
// alone: `epa tuning export` writes one, `epa tuning import` reads it back into a store.
//
//   schema = "epa-tuning/1"
//   name = "paper"
//   source = "seeded from config/"
//   controller = "pp-ffidz"
//   lc_mm = 5.0
//   valve_limit_v = 5.0
//   design = "{}"                 # the design spec (JSON text) that produced F, G, H
//   [rst]
//   F = [1.0, -1.778, 0.7828]
//   G = [-0.1734, 0.577, -0.3958]
//   H = [-0.1734, 0.577, -0.3958]
//   [dead_zone]                   # what NG-IDZ and FF-IDZ invert, V
//   m_r = 1.7627  m_l = 1.0707  b_r = 1.232  b_l = -1.722
//   [model]                       # epa-model/1 keys, plus name and fit
//   name = "paper"  source = "..."  Ts = 0.005  mm_per_volt = 50.0  fit = "{}"
//   axis_model = "stick-slip"  identified_drive_v = [-3.0, 3.0]   # optional, as in a model file
//   [model.arx]        A = [...]  B = [...]
//   [model.dead_zone]  m_r = ...
//   [model.stick_slip]         break_right_v = ...   # optional, as in a model file
//   [model.stick_slip_spread]  friction_log_ratio = ...
#include <string>

#include "core/result.hpp"
#include "store/model_record.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

struct TuningFile {
  TuningSet set;     // id and model_id 0
  ModelRecord model; // id 0
};

std::string format_tuning_toml(const TuningSet& set, const ModelRecord& model);

// Errors name the file and line (syntax) or the key; unknown keys are refused; the set is
// validated with its model, so a file that imports is a set the loop accepts.
core::Result<TuningFile> parse_tuning_toml(const std::string& text, const std::string& source_name);

}  // namespace epa::store
