#include "plant/stick_slip_model.hpp"

#include <cmath>
#include <string>

#include "core/format.hpp"
#include "core/reading_slope.hpp"

namespace epa::plant {

core::Result<StickSlipModel> StickSlipModel::make(const StickSlipParams& params, double Ts, int substeps) {
  if (auto s = params.validate(); !s) return s.error();
  if (!(Ts > 0.0) || !std::isfinite(Ts)) return core::invalid_argument("stick-slip model: Ts must be > 0");
  if (substeps < 1 || substeps > 64) return core::invalid_argument("stick-slip model: substeps must be within 1..64");
  // The explicit sub-steps stay stable (and accurate enough) only while one sub-step is short
  // against the spring's period and the damping's time constant.
  const double h = Ts / substeps;
  if (params.spring_rad_s * h > kMaxStiffnessPerStep || 2.0 * params.damping_ratio * params.spring_rad_s * h > kMaxStiffnessPerStep)
    return core::invalid_argument("stick-slip model: spring_rad_s " + std::to_string(params.spring_rad_s) + " with damping_ratio " +
                                  std::to_string(params.damping_ratio) + " is too stiff for sub-steps of " +
                                  std::to_string(h * 1e3) + " ms (omega h and 2 zeta omega h must stay <= 1)");
  return StickSlipModel(params, Ts, substeps);
}

StickSlipModel::StickSlipModel(const StickSlipParams& params, double Ts, int substeps)
    : p_(params), h_s_(Ts / substeps), substeps_(substeps) {
  spool_gain_ = h_s_ / (p_.spool_lag_s + h_s_);
  omega2_ = p_.spring_rad_s * p_.spring_rad_s;
  two_zeta_omega_ = 2.0 * p_.damping_ratio * p_.spring_rad_s;
}

void StickSlipModel::reset(double position_mm) noexcept {
  delay_line_.fill(0.0);
  delay_head_ = 0;
  spool_v_ = z_mm_ = v_mm_s_ = 0.0;
  y_mm_ = position_mm;
  stuck_ = true;
}

double StickSlipModel::step(double valve_v) noexcept {
  // The delay line: u(k - delay) leaves as u(k) enters.
  const std::size_t length = static_cast<std::size_t>(p_.delay_samples) + 1;
  delay_line_[delay_head_] = std::isfinite(valve_v) ? valve_v : 0.0;
  const double u = delay_line_[(delay_head_ + 1) % length];
  delay_head_ = (delay_head_ + 1) % length;

  for (int i = 0; i < substeps_; ++i) {
    spool_v_ += spool_gain_ * (u - spool_v_);
    double w = 0.0;
    if (spool_v_ > p_.break_right_v) w = p_.speed_right_mm_s_per_v * (spool_v_ - p_.break_right_v);
    else if (spool_v_ < p_.break_left_v) w = p_.speed_left_mm_s_per_v * (spool_v_ - p_.break_left_v);
    z_mm_ += h_s_ * (w - v_mm_s_);
    if (stuck_) {
      if (std::abs(z_mm_) <= p_.static_mm) continue;
      stuck_ = false;
    }
    // Sliding friction opposes the motion; at v = 0 (just broken away) it opposes the wind-up.
    const double direction = v_mm_s_ != 0.0 ? std::copysign(1.0, v_mm_s_) : std::copysign(1.0, z_mm_);
    const double a = omega2_ * (z_mm_ - p_.coulomb_mm * direction) - two_zeta_omega_ * v_mm_s_;
    double v_next = v_mm_s_ + h_s_ * a;
    if (v_mm_s_ != 0.0 && v_next * v_mm_s_ < 0.0) {  // reversal within the sub-step: it ends at rest
      v_next = 0.0;
      stuck_ = std::abs(z_mm_) <= p_.static_mm;
    } else if (v_mm_s_ == 0.0 && v_next * direction < 0.0) {  // friction cannot start a motion
      v_next = 0.0;
    }
    y_mm_ += 0.5 * h_s_ * (v_mm_s_ + v_next);
    v_mm_s_ = v_next;
  }
  return y_mm_;
}

double ramp_start_v(const StickSlipParams& params, double Ts, double ramp_v_per_s, double direction, double travel_mm) {
  auto model = StickSlipModel::make(params, Ts);
  if (!model || !(ramp_v_per_s > 0.0)) return NAN;
  model->reset(0.0);
  const double step_v = direction * ramp_v_per_s * Ts;
  for (int k = 1; std::abs(step_v * k) <= 10.0; ++k) {
    const double u = step_v * k;
    if (std::abs(model->step(u)) >= travel_mm) return u;
  }
  return NAN;
}

double coast_time_s(const StickSlipParams& params, double Ts, double speed_mm_s) {
  double sum_s = 0.0;
  int directions = 0;
  for (const double direction : {1.0, -1.0}) {
    auto model = StickSlipModel::make(params, Ts);
    if (!model || !(speed_mm_s > 0.0)) return NAN;
    model->reset(0.0);
    const double u = direction > 0.0 ? params.break_right_v + speed_mm_s / params.speed_right_mm_s_per_v
                                     : params.break_left_v - speed_mm_s / params.speed_left_mm_s_per_v;
    std::array<double, 4> y{};  // newest first
    const int steady_samples = static_cast<int>(std::ceil(1.0 / Ts));
    for (int k = 0; k < steady_samples; ++k) {
      for (std::size_t i = y.size() - 1; i > 0; --i) y[i] = y[i - 1];
      y[0] = model->step(u);
    }
    const double speed = direction * core::slope_of_last_four(y, Ts);
    if (!(speed > 0.0)) continue;
    for (int k = 0; k < steady_samples && !(model->stuck() && k > params.delay_samples); ++k) model->step(0.0);
    sum_s += direction * (model->position_mm() - y[0]) / speed;
    ++directions;
  }
  return directions > 0 ? sum_s / directions : NAN;
}

core::Result<double> sliding_arrival_coast_s(const core::ModelFile& file, double approach_speed_mm_s) {
  if (file.axis_model != core::AxisModel::kStickSlip || !file.stick_slip) return 0.0;
  const double coast_s = coast_time_s(*file.stick_slip, file.model.Ts, approach_speed_mm_s);
  if (!std::isfinite(coast_s))
    return core::invalid_argument("the model's [stick_slip] table does not slide at pp-traj's approach speed (" +
                                  core::format_number(approach_speed_mm_s) + " mm/s): no coast time for its arrival");
  return coast_s;
}

}  // namespace epa::plant
