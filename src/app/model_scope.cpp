#include "app/model_scope.hpp"

#include <algorithm>

#include "diag/stick_slip_spread.hpp"

namespace epa::app {

std::array<double, 2> identified_drive_v(std::span<const core::Run* const> estimation) {
  std::array<double, 2> range{0.0, 0.0};
  for (const auto* run : estimation)
    for (const double u : run->u_V) range[0] = std::min(range[0], u), range[1] = std::max(range[1], u);
  return range;
}

core::StickSlipSpread model_spread(const core::StickSlipParams& params, double Ts, std::span<const core::Run* const> validation,
                                   const std::array<double, 2>& drive_v) {
  diag::JudgedScope scope;
  scope.drive_lo_v = drive_v[0], scope.drive_hi_v = drive_v[1];
  return diag::stick_slip_spread(params, Ts, validation, scope);
}

}  // namespace epa::app
