#pragma once
// Model files (TOML, `epa-model/1`): a Hammerstein model that `epa design` and `epa simulate`
// accept with --model and that `epa identify` writes. config/paper-model.toml is the paper's.
//
//   schema = "epa-model/1"
//   Ts = 0.005            # s
//   mm_per_volt = 50.0    # sensor scale
//   source = "..."        # free text: where the model came from
//   axis_model = "stick-slip"  # optional: which of the file's models describes the axis ("hammerstein"
//                         # when left out); "stick-slip" needs [stick_slip], and makes pp-traj arrive
//                         # while sliding (control/sliding_approach.hpp)
//   identified_drive_v = [-3.0, 3.0]  # optional: the lowest and highest valve command the model was
//                         # identified on; epa diagnose judges it inside them (it extrapolates outside)
//   [arx]
//   A = [1.0, -0.9094, -0.6110, 0.5204]   # coefficients of q^0, q^-1, ...
//   B = [0.0, 1.024, -2.046, 1.029]
//   [dead_zone]
//   m_r = 1.7627
//   m_l = 1.0707
//   b_r = 1.232     # V
//   b_l = -1.722    # V
//   [stick_slip]    # optional: the stick-slip model `epa identify` fits beside it (core/stick_slip_params.hpp)
//   break_right_v = 1.17
//   ...             # every field of StickSlipParams, by its name; delay_samples an integer
//   [stick_slip_spread]  # optional: how far its terms move between parts of the identification runs
//   friction_log_ratio = 0.3  # ... every field of StickSlipSpread, by its name
#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "core/stick_slip_params.hpp"

namespace epa::core {

// Which model describes the axis: epa identify's verdict, the one that follows held-out runs better.
enum class AxisModel { kHammerstein, kStickSlip };

// "hammerstein", "stick-slip": the name model files, tuning files and the store give it.
std::string_view to_string(AxisModel axis_model);
std::optional<AxisModel> parse_axis_model(std::string_view name);

// identified_drive_v's rule: [lowest, highest] valve command, V, within [-10, 0] and [0, 10].
inline bool identified_drive_v_valid(const std::array<double, 2>& v) {
  return v[0] <= 0.0 && v[1] >= 0.0 && v[0] >= -10.0 && v[1] <= 10.0;
}

// Fits closer than this are equal (as order selection's tolerance holds two orders' to be).
inline constexpr double kAxisModelMarginPct = 0.5;

// The verdict from the two models' free-run fits on the same runs (held-out ones when there are
// any), for epa identify and epa commission alike: the stick-slip model only when it follows them
// better by more than kAxisModelMarginPct; within that, the Hammerstein model, the linear one the
// laws are designed on (67.4 against 67.3 % is no evidence of stick-slip).
inline AxisModel axis_model_from_fits(double stick_slip_fit_pct, double hammerstein_fit_pct) {
  return stick_slip_fit_pct > hammerstein_fit_pct + kAxisModelMarginPct ? AxisModel::kStickSlip : AxisModel::kHammerstein;
}

struct ModelFile {
  HammersteinModel model;
  std::string source;  // provenance text
  std::optional<StickSlipParams> stick_slip = std::nullopt;  // the axis as a stick-slip model, when identified
  AxisModel axis_model = AxisModel::kHammerstein;
  std::optional<std::array<double, 2>> identified_drive_v = std::nullopt;  // V: lowest, highest
  std::optional<StickSlipSpread> stick_slip_spread = std::nullopt;          // needs stick_slip
};

// Errors name the file, and the line for syntax errors, and the key that is missing or wrong.
Result<ModelFile> parse_model_toml(const std::string& text, const std::string& source_name);
Result<ModelFile> read_model_file(const std::string& path);
std::string format_model_toml(const ModelFile& file);
// The [dead_zone] table, header and one line per key, as the model file and the tuning file write it.
std::string format_dead_zone_table(const DeadZone& dead_zone);
Status write_model_file(const std::string& path, const ModelFile& file);

}  // namespace epa::core
