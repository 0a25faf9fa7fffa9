#pragma once
// The parameters of the stick-slip model of a pneumatic axis (plant/stick_slip_model.hpp has the
// equations and why; ident/stick_slip_fit.hpp fits them; model files carry them as [stick_slip]).
// Per unit of moving mass, so every value is readable without knowing the mass or the stiffness.

#include <array>
#include <string_view>
#include <utility>

#include "core/result.hpp"

namespace epa::core {

struct StickSlipParams {
  double break_right_v = 1.2;            // flow starts above this command (spool overlap)
  double break_left_v = -1.7;            // and below this one
  double speed_right_mm_s_per_v = 100.0; // steady speed per volt beyond break_right, friction aside
  double speed_left_mm_s_per_v = 100.0;  // the same beyond break_left
  double spring_rad_s = 50.0;            // the air spring's natural frequency against the moving mass
  double damping_ratio = 0.3;            // of that spring-mass mode
  double coulomb_mm = 5.0;               // sliding friction, as the air spring's wind-up that balances it
  double static_mm = 8.0;                // breakaway (>= coulomb_mm), the same unit
  double spool_lag_s = 0.01;             // first-order valve lag (0: none)
  int delay_samples = 1;                 // dead time of the command, whole samples (0..kMaxDelay)

  static constexpr int kMaxDelay = 8;
  Status validate() const;  // the message names the field
  bool operator==(const StickSlipParams&) const = default;
};

// The real-valued fields by the name model files, tuning files and the store give them, in their
// order there (delay_samples, a whole number, follows them): one list, so the readers and writers agree.
inline constexpr std::array<std::pair<std::string_view, double StickSlipParams::*>, 9> kStickSlipFields = {{
    {"break_right_v", &StickSlipParams::break_right_v},
    {"break_left_v", &StickSlipParams::break_left_v},
    {"speed_right_mm_s_per_v", &StickSlipParams::speed_right_mm_s_per_v},
    {"speed_left_mm_s_per_v", &StickSlipParams::speed_left_mm_s_per_v},
    {"spring_rad_s", &StickSlipParams::spring_rad_s},
    {"damping_ratio", &StickSlipParams::damping_ratio},
    {"coulomb_mm", &StickSlipParams::coulomb_mm},
    {"static_mm", &StickSlipParams::static_mm},
    {"spool_lag_s", &StickSlipParams::spool_lag_s},
}};

// How far the stick-slip model's terms move when it is re-fitted on parts of its own
// identification runs (epa identify: parts of 15 s of the validation runs, diag/stick_slip_spread.hpp).
// A change of the axis smaller than this cannot be told from the model's own error in some regime
// of motion (a model fitted mostly on pulses reads slow ramps with more friction). Ratios as
// |ln ratio|, the rest as the largest deviation.
struct StickSlipSpread {
  double friction_log_ratio = 0.0;
  double flow_gain_log_ratio = 0.0;
  double break_v = 0.0;
  double spool_lag_s = 0.0;
  double delay_samples = 0.0;
  Status validate() const;  // every field finite and >= 0; the message names it
  bool operator==(const StickSlipSpread&) const = default;
};

// Every field by its name in files and the store, in their order there.
inline constexpr std::array<std::pair<std::string_view, double StickSlipSpread::*>, 5> kStickSlipSpreadFields = {{
    {"friction_log_ratio", &StickSlipSpread::friction_log_ratio},
    {"flow_gain_log_ratio", &StickSlipSpread::flow_gain_log_ratio},
    {"break_v", &StickSlipSpread::break_v},
    {"spool_lag_s", &StickSlipSpread::spool_lag_s},
    {"delay_samples", &StickSlipSpread::delay_samples},
}};

}  // namespace epa::core
