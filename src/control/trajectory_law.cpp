#include "control/trajectory_law.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/first_order_lag.hpp"
#include "core/format.hpp"

namespace epa::control {

namespace {

double sum_of(const core::Polynomial& p) {
  double s = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) s += p[i];
  return s;
}

core::Error field_error(const std::string& field, double value, const std::string& expected) {
  return core::invalid_argument("pp-traj: " + field + " = " + core::format_number(value) + ": expected " + expected);
}

}  // namespace

core::Result<ModelSpeeds> model_top_speeds(const core::Polynomial& A, const core::Polynomial& B, const core::DeadZone& dz,
                                           double valve_limit_v, double Ts) {
  const double b1 = sum_of(B);
  double a_slope = 0.0;  // A1(1) = -A'(1) = -sum i a_i when A(1) = 0
  double a_scale = 0.0;
  for (std::size_t i = 0; i < A.size(); ++i) {
    a_slope -= static_cast<double>(i) * A[i];
    a_scale += std::abs(A[i]);
  }
  const double a1 = sum_of(A);
  if (!(std::abs(a1) <= 1e-3 * a_scale))
    return core::invalid_argument("pp-traj needs a model that integrates (A(1) = 0, valve opening -> speed); A(1) = " +
                                  core::format_number(a1));
  if (!(b1 > 0.0) || !(a_slope > 0.0))
    return core::invalid_argument("pp-traj needs a model whose static speed gain B(1) / A1(1) is positive; B(1) = " +
                                  core::format_number(b1) + ", A1(1) = " + core::format_number(a_slope));
  const double per_u = b1 / (a_slope * Ts);  // V/s of speed per unit of u_d
  ModelSpeeds s;
  s.per_u_v_s = per_u;
  s.pos_v_s = std::max(0.0, dz.m_r * (valve_limit_v - dz.b_r)) * per_u;
  s.neg_v_s = std::max(0.0, dz.m_l * (valve_limit_v + dz.b_l)) * per_u;
  if (!(s.pos_v_s > 0.0) || !(s.neg_v_s > 0.0))
    return core::invalid_argument("pp-traj: the valve limit " + core::format_number(valve_limit_v) +
                                  " V lies inside the dead zone: the model cannot move");
  return s;
}

core::Result<TrajectoryParams> make_trajectory_params(const TrajectoryConfig& c, const core::Polynomial& A,
                                                      const core::Polynomial& B, const core::DeadZone& dz,
                                                      double valve_limit_v, double Ts) {
  if (!(Ts > 0.0) || !std::isfinite(Ts)) return field_error("Ts", Ts, "> 0 s");
  if (A.size() == 0 || B.size() == 0) return core::invalid_argument("pp-traj needs the model's A and B");
  if (A.size() > kMaxLawOrder + 1 || B.size() > kMaxLawOrder + 1)
    return core::invalid_argument("pp-traj: the model's order is above " + std::to_string(kMaxLawOrder));
  if (!(c.speed_fraction > 0.0 && c.speed_fraction <= 1.0)) return field_error("speed_fraction", c.speed_fraction, "in (0, 1]");
  if (!(c.accel_v_s2 >= 0.0) || !std::isfinite(c.accel_v_s2)) return field_error("accel", c.accel_v_s2, ">= 0 (0: derived)");
  if (!(c.accel_per_distance >= 0.0) || !std::isfinite(c.accel_per_distance))
    return field_error("accel_per_distance", c.accel_per_distance, ">= 0 1/s^2 (0: off)");
  if (!(c.smoothing_s >= 0.0) || !std::isfinite(c.smoothing_s)) return field_error("smoothing_s", c.smoothing_s, ">= 0 s");
  if (!(c.feedback_bandwidth_rad_s > 0.0) || !std::isfinite(c.feedback_bandwidth_rad_s))
    return field_error("feedback_bandwidth_rad_s", c.feedback_bandwidth_rad_s, "> 0 rad/s");
  if (!(c.filter_ratio > 0.0) || !std::isfinite(c.filter_ratio)) return field_error("filter_ratio", c.filter_ratio, "> 0");
  if (!(c.integral_gain_per_s >= 0.0) || !std::isfinite(c.integral_gain_per_s))
    return field_error("integral_gain", c.integral_gain_per_s, ">= 0 (0: derived)");
  if (!(c.integrator_band_v >= 0.0) || !std::isfinite(c.integrator_band_v)) return field_error("integrator_band", c.integrator_band_v, ">= 0");
  if (!(c.hold_band_v >= 0.0) || !std::isfinite(c.hold_band_v)) return field_error("hold_band", c.hold_band_v, ">= 0");
  if (!(c.error_filter_s >= 0.0) || !std::isfinite(c.error_filter_s)) return field_error("error_filter_s", c.error_filter_s, ">= 0 s");
  if (!(c.creep_margin_v >= 0.0) || !std::isfinite(c.creep_margin_v)) return field_error("creep_margin_v", c.creep_margin_v, ">= 0 V");
  if (!(c.idz_ramp >= 0.0) || !std::isfinite(c.idz_ramp)) return field_error("idz_ramp", c.idz_ramp, ">= 0");
  if (!(c.creep_blend_s >= 0.0) || !std::isfinite(c.creep_blend_s)) return field_error("creep_blend_s", c.creep_blend_s, ">= 0 s");
  if (!(c.coast_s >= 0.0) || !std::isfinite(c.coast_s)) return field_error("coast_s", c.coast_s, ">= 0 s (0: off)");
  if (!(c.in_position_window_v >= 0.0) || !std::isfinite(c.in_position_window_v))
    return field_error("in_position_window", c.in_position_window_v, ">= 0 V (0: none)");
  if (c.coast_s > 0.0) {
    if (!(c.approach_speed_v_s > 0.0) || !std::isfinite(c.approach_speed_v_s))
      return field_error("approach_speed", c.approach_speed_v_s, "> 0");
    if (!(c.approach_length_v > 0.0) || !std::isfinite(c.approach_length_v))
      return field_error("approach_length", c.approach_length_v, "> 0");
    if (!(c.approach_decel_v_s2 > 0.0) || !std::isfinite(c.approach_decel_v_s2))
      return field_error("approach_decel", c.approach_decel_v_s2, "> 0");
    if (!(c.retry_band_v > 0.0) || !std::isfinite(c.retry_band_v)) return field_error("retry_band", c.retry_band_v, "> 0");
    if (!(c.max_retries >= 0.0 && c.max_retries <= 10.0 && c.max_retries == std::floor(c.max_retries)))
      return field_error("max_retries", c.max_retries, "a whole number 0..10");
    if (!(c.approach_settle_s > 0.0 && c.approach_settle_s <= 10.0))
      return field_error("approach_settle_s", c.approach_settle_s, "in (0, 10] s");
    if (!(c.coast_dead_length_v > 0.0) || !std::isfinite(c.coast_dead_length_v))
      return field_error("coast_dead_length", c.coast_dead_length_v, "> 0");
    if (!std::isfinite(c.travel_min_v) || !(c.travel_max_v > c.travel_min_v) || !std::isfinite(c.travel_max_v))
      return field_error("travel_max", c.travel_max_v, "finite and above travel_min " + core::format_number(c.travel_min_v));
  }
  for (std::size_t i = 0; i < A.size(); ++i)
    if (!std::isfinite(A[i])) return core::invalid_argument("pp-traj: the model's A[" + std::to_string(i) + "] is not finite");
  for (std::size_t i = 0; i < B.size(); ++i)
    if (!std::isfinite(B[i])) return core::invalid_argument("pp-traj: the model's B[" + std::to_string(i) + "] is not finite");
  auto speeds = model_top_speeds(A, B, dz, valve_limit_v, Ts);
  if (!speeds) return speeds.error();

  TrajectoryParams p;
  const double smoothing = std::round(c.smoothing_s / Ts);
  if (smoothing > static_cast<double>(kMaxSmoothingSamples))
    return field_error("smoothing_s", c.smoothing_s,
                       "at most " + std::to_string(kMaxSmoothingSamples) + " samples (" + core::format_number(kMaxSmoothingSamples * Ts) + " s)");
  p.limits.smoothing_samples = std::max<std::size_t>(1, static_cast<std::size_t>(smoothing));
  p.limits.Ts = Ts;
  p.limits.speed_pos_v_s = c.speed_fraction * speeds->pos_v_s;
  p.limits.speed_neg_v_s = c.speed_fraction * speeds->neg_v_s;
  const double slow = std::min(p.limits.speed_pos_v_s, p.limits.speed_neg_v_s);
  p.limits.accel_v_s2 = c.accel_v_s2 > 0.0 ? c.accel_v_s2 : slow / 0.03;  // top speed within 30 ms
  p.limits.accel_per_distance = c.accel_per_distance;
  const double b1 = sum_of(B);
  for (std::size_t i = 0; i < A.size(); ++i) p.A[i] = A[i] / b1;
  for (std::size_t i = 0; i < B.size(); ++i) p.B[i] = B[i] / b1;
  p.nA = A.size() - 1;
  p.nB = B.size() - 1;
  p.proportional_gain = c.feedback_bandwidth_rad_s / speeds->per_u_v_s;  // crossover on the model's integrator
  p.feedback_filter_alpha = 1.0 - std::exp(-c.filter_ratio * c.feedback_bandwidth_rad_s * Ts);
  p.integral_gain = c.integral_gain_per_s > 0.0 ? c.integral_gain_per_s : 0.75 * p.proportional_gain * c.feedback_bandwidth_rad_s;
  p.integrator_band_v = c.integrator_band_v;
  p.hold_band_v = c.hold_band_v;
  p.filter_alpha = core::lag_step_share(c.error_filter_s, Ts);
  p.idz_ramp = c.idz_ramp;
  p.creep_margin_v = c.creep_margin_v;
  p.creep_margin_step_v = c.creep_margin_v / std::max(1.0, std::round(c.creep_blend_s / Ts));
  p.integrator_limit = std::max(dz.m_r * (valve_limit_v - dz.b_r), dz.m_l * (valve_limit_v + dz.b_l));
  // The sliding arrival: the law's own when coast_s > 0, else (coast_s 0) only its fallback's.
  p.sliding_approach = c.coast_s > 0.0;
  p.approach.coast_s = c.coast_s;
  p.approach.dead_length_v = c.coast_dead_length_v;
  p.approach.speed_v_s = c.approach_speed_v_s;
  p.approach.length_v = c.approach_length_v;
  p.approach.decel_v_s2 = c.approach_decel_v_s2;
  p.approach.top_speed_pos_v_s = p.limits.speed_pos_v_s;
  p.approach.top_speed_neg_v_s = p.limits.speed_neg_v_s;
  p.approach.accel_v_s2 = p.limits.accel_v_s2;
  p.approach.retry_band_v = c.retry_band_v;
  p.approach.max_retries = static_cast<int>(c.max_retries);
  p.approach.settle_samples = static_cast<std::size_t>(std::max(1.0, std::round(c.approach_settle_s / Ts)));
  p.approach.Ts = Ts;
  p.approach.travel_min_v = c.travel_min_v;
  p.approach.travel_max_v = c.travel_max_v;
  p.approach.short_approach_band_v = kStopShareOfWindow * c.in_position_window_v;
  p.approach.short_approach_accel_v_s2 =
      std::min(c.approach_speed_v_s * c.approach_speed_v_s / (2.0 * kShortApproachRunUpV), p.approach.accel_v_s2);
  p.fallback_approach = p.approach;
  p.fallback_approach.coast_s = kFallbackCoastS;
  p.fallback_approach.retry_band_v = std::max(p.approach.retry_band_v, p.approach.short_approach_band_v);
  return p;
}

void trajectory_reset(const TrajectoryParams& p, TrajectoryState& s, double y_v, double speed_v_s) noexcept {
  s = {};
  motion_profile_reset(p.limits, s.profile, y_v, speed_v_s);
  for (std::size_t i = 0; i < s.w.size(); ++i) s.w[i] = y_v - s.profile.speed_v_s * p.limits.Ts * static_cast<double>(i);
}

namespace {

// w(k) into the reference history; returns what the model's output does under it (y_d) and the
// feed-forward that makes it so (u_ff): y_d = B w / B(1), u_ff = A w / B(1).
struct ModelTracking {
  double y_d = 0.0, u_ff = 0.0;
};
ModelTracking push_reference(const TrajectoryParams& p, TrajectoryState& s, double w_v) noexcept {
  for (std::size_t i = kMaxLawOrder; i > 0; --i) s.w[i] = s.w[i - 1];
  s.w[0] = w_v;
  ModelTracking t;
  for (std::size_t i = 0; i <= p.nB; ++i) t.y_d += p.B[i] * s.w[i];
  for (std::size_t i = 0; i <= p.nA; ++i) t.u_ff += p.A[i] * s.w[i];
  return t;
}

// The proportional feedback on the tracking error e through its second-order low-pass.
double feedback_step(const TrajectoryParams& p, TrajectoryState& s, double e) noexcept {
  s.feedback_stage1_v += p.feedback_filter_alpha * (e - s.feedback_stage1_v);
  s.feedback_stage2_v += p.feedback_filter_alpha * (s.feedback_stage1_v - s.feedback_stage2_v);
  return p.proportional_gain * s.feedback_stage2_v;
}

// pp-traj with arrival while sliding: the approach's reference through the same feed-forward and
// feedback, the valve centred from the cut on.
TrajectoryOutput approach_trajectory_step(const TrajectoryParams& p, const ApproachLimits& limits, TrajectoryState& s, double r_v,
                                          double y_v) noexcept {
  const ApproachOutput a = approach_step(limits, s.approach, r_v, y_v);
  TrajectoryOutput out;
  if (a.hold) {
    s.holding = true;
    out.holding = true;
    out.arrived = true;
    return out;
  }
  if (a.leg_started) {  // a reference that has run at its speed so far (0: at rest), nothing filtered
    for (std::size_t i = 0; i < s.w.size(); ++i) s.w[i] = a.w_v - a.speed_v_s * p.limits.Ts * static_cast<double>(i + 1);
    s.feedback_stage1_v = s.feedback_stage2_v = s.filtered_error_v = 0.0;
  }
  s.holding = false;
  const ModelTracking t = push_reference(p, s, a.w_v);
  out.u = a.drive_fraction * (t.u_ff + feedback_step(p, s, t.y_d - y_v));
  return out;
}

}  // namespace

void trajectory_fall_back_to_sliding(TrajectoryState& s, double approach_direction) noexcept {
  s.sliding_fallback = true;
  s.approach.phase = ApproachPhase::kIdle;  // plans from the piston at the next sample; its readings stay
  s.approach.next_direction = approach_direction;
  s.last_r_v = NAN;
  s.reference_changes = 0;
  s.following_reference = false;
}

TrajectoryOutput trajectory_step(const TrajectoryParams& p, TrajectoryState& s, double r_v, double y_v,
                                 int saturated_sign_last) noexcept {
  if (!s.profile.started) trajectory_reset(p, s, y_v);
  if (p.sliding_approach || s.sliding_fallback) {
    const ApproachLimits& limits = p.sliding_approach ? p.approach : p.fallback_approach;
    s.reference_changes = r_v != s.last_r_v ? std::min(s.reference_changes + 1, 2) : 0;
    s.last_r_v = r_v;
    if (s.reference_changes < 2) {
      if (s.following_reference) {  // the reference stands: arrive from the piston, or hold where it stops
        s.following_reference = false;
        approach_after_moving_reference(limits, s.approach, r_v, y_v);
      }
      return approach_trajectory_step(p, limits, s, r_v, y_v);
    }
    if (!s.following_reference) {  // the reference moves: the profile law from the piston, at its speed
      const ApproachState approach = s.approach;  // its readings and the coast it learned
      const bool fallback = s.sliding_fallback;
      trajectory_reset(p, s, y_v, approach_speed_v_s(approach, p.limits.Ts));
      s.approach = approach;
      s.sliding_fallback = fallback;
      s.last_r_v = r_v;
      s.reference_changes = 2;
      s.following_reference = true;
    }
    approach_observe(s.approach, y_v);
  }
  const ModelTracking t = push_reference(p, s, motion_profile_step(p.limits, s.profile, r_v));

  // The tracking error against what the model's output does, not against r: y_d reaches r a few
  // samples after the profile (B's delay), and an integrator fed r - y meanwhile would wind up.
  const double e = t.y_d - y_v;
  s.filtered_error_v += p.filter_alpha * (e - s.filtered_error_v);
  bool arrived = motion_profile_arrived(p.limits, s.profile, r_v);
  for (std::size_t i = 0; arrived && i <= std::max(p.nA, p.nB); ++i) arrived = s.w[i] == r_v;
  const double ef = s.filtered_error_v;
  // Leaving the target: the integral goes. It was wound up against the creeping inverse, which
  // stops creep_margin_v short of the break points, and NG-IDZ while moving has no such margin:
  // carried into the move it drove the piston ahead of its path (1.7 mm at 15 mm/s on the printed
  // model, and a halt that braked from the piston then ran 3 mm past its stop).
  if (s.arrived && !arrived) s.integral = 0.0;
  s.arrived = arrived;
  if (!arrived) {
    s.holding = false;
  } else if (s.holding) {
    s.holding = std::abs(ef) <= p.hold_band_v;
  } else {
    s.holding = std::abs(ef) <= 0.5 * p.hold_band_v;  // enter at half the band: hysteresis
  }
  if (arrived && !s.holding && std::abs(ef) > p.integrator_band_v) {
    const int direction = (ef > 0.0) - (ef < 0.0);
    if (direction != saturated_sign_last)  // anti-windup: no integrating further into the limit
      s.integral = std::clamp(s.integral + p.integral_gain * p.limits.Ts * ef, -p.integrator_limit, p.integrator_limit);
  }
  const double u_fb = feedback_step(p, s, e);
  // The creeping inverse takes over from NG-IDZ gradually: a margin that jumped at arrival would
  // step the drive by up to the margin's worth, and the printed B answers a step of its drive with
  // a spike at the Nyquist rate (docs/paper.md), on a plant whose dead band or gain is not the model's.
  s.creep_margin_v = arrived ? std::min(p.creep_margin_v, s.creep_margin_v + p.creep_margin_step_v) : 0.0;
  TrajectoryOutput out;
  out.u = t.u_ff + u_fb + s.integral;
  out.holding = s.holding;
  out.arrived = arrived;
  out.creep_margin_v = s.creep_margin_v;
  return out;
}

}  // namespace epa::control
