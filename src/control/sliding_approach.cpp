#include "control/sliding_approach.hpp"

#include <algorithm>
#include <cmath>

#include "core/reading_slope.hpp"
#include "core/units.hpp"

namespace epa::control {

namespace {

double mean_reading(const ApproachState& s) noexcept {
  const std::size_t n = std::max<std::size_t>(1, std::min(s.reading_count, s.readings.size()));
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += s.readings[i];
  return sum / static_cast<double>(n);
}

// Least-squares slope of the last 4 readings (V/s); 0 until there are 4.
double reading_slope(const ApproachState& s, double Ts) noexcept {
  if (s.reading_count < 4) return 0.0;
  return core::slope_of_last_four(s.readings, Ts);
}

void hold(ApproachState& s, double at_v) noexcept {
  s.phase = ApproachPhase::kHolding;
  s.held_at_v = at_v;
  s.samples_in_phase = 0;
}

std::size_t direction_index(double direction) noexcept { return direction > 0.0 ? 0 : 1; }

constexpr double kSensorSpanV = core::mm_to_sensor_v(core::kStrokeMm);  // the stroke's ends at 0 and this
// Each direction's offset is the running mean of what its stops asked for (gain 1, 1/2, 1/3), then
// of about the last 4 (gain 1/4): on the commissioning test's rig through its remote I/O a stop
// scatters by +-0.8 mm about what the coast predicts, and with a gain of 1 the retries chased that
// scatter (one run in two used all 3 retries on a move, alternating 0.8 mm short and past). Offline on that rig with 0.05 mm noise, a jittering 1-2 sample I/O delay and 40 moves:
// 2-10 retries in all and no move with 3, against 1-16 and 5 moves with 3 at a gain of 1.
constexpr int kLearningMemory = 4;

// Where an approach starts: one approach length before the target, or as far as the travel
// allows when the target lies nearer than that to its end (the approach is then shorter).
double back_off_point_v(const ApproachLimits& l, const ApproachState& s) noexcept {
  return std::clamp(s.planned_r_v - s.final_direction * l.length_v, l.travel_min_v, l.travel_max_v);
}

// The target lies nearer than one approach length to the end of the travel it is approached from.
bool travel_cuts_the_approach(const ApproachLimits& l, const ApproachState& s) noexcept {
  return back_off_point_v(l, s) != s.planned_r_v - s.final_direction * l.length_v;
}

// A leg from the piston at from_v; the path starts at the piston's speed along it when the piston
// slides that way (a setpoint changed mid-move does not first stop the piston), else from rest.
void start_leg(const ApproachLimits& l, ApproachState& s, double target_v, double direction, bool final_leg, double from_v) noexcept {
  s.phase = ApproachPhase::kLeg;
  s.leg_target_v = target_v;
  s.leg_direction = direction;
  s.final_leg = final_leg;
  s.path_v = from_v;
  s.leg_coast_s = std::max(0.0, coast_at_s(l, target_v) + s.learned_offset_s[direction_index(s.final_direction)]);
  const double sliding = direction * reading_slope(s, l.Ts);
  s.path_speed_v_s = sliding >= 0.5 * l.speed_v_s ? sliding : 0.0;
  s.short_approach = final_leg && s.path_speed_v_s == 0.0 && travel_cuts_the_approach(l, s) &&
                     direction * (target_v - from_v) < l.length_v;
  s.samples_in_phase = 0;
}

// The back-off before an approach, from where the piston is.
void back_off(const ApproachLimits& l, ApproachState& s, double y_v) noexcept {
  const double to_v = back_off_point_v(l, s);
  start_leg(l, s, to_v, y_v < to_v ? 1.0 : -1.0, false, y_v);
}

// Plans a move to r from the piston at y: straight in when it is at least one approach long or the
// piston already slides towards r, else back off first so that the final approach is a whole one.
void plan(const ApproachLimits& l, ApproachState& s, double r_v, double y_v) noexcept {
  s.planned_r_v = r_v;
  s.retries = 0;
  s.short_approach = false;
  const double move = r_v - y_v;
  if (std::abs(move) <= l.retry_band_v) {
    hold(s, y_v);
    return;
  }
  s.final_direction = s.next_direction != 0.0 ? s.next_direction : move > 0.0 ? 1.0 : -1.0;
  s.next_direction = 0.0;
  // Straight in when the move is a whole approach long, or when the piston already slides towards
  // the target (a setpoint that moved and stopped ahead of it): the back-off is for starts from rest.
  // Straight in too when the travel leaves no room to back off (a target near an end, the piston
  // between it and that end): the approach never comes from the target's far side, where a gripper
  // or a part may stand.
  const bool sliding_towards = s.final_direction * reading_slope(s, l.Ts) >= 0.5 * l.speed_v_s;
  const bool no_room = s.final_direction * (back_off_point_v(l, s) - y_v) >= -l.retry_band_v;
  const bool straight_in = s.final_direction * move >= l.length_v || sliding_towards || no_room;
  if (straight_in)
    start_leg(l, s, r_v, s.final_direction, true, y_v);
  else
    back_off(l, s, y_v);
}

}  // namespace

double coast_at_s(const ApproachLimits& l, double x_v) noexcept {
  const auto compliance = [&](double x) {  // 1 / stiffness, up to the factor they share
    x = std::clamp(x, 0.0, kSensorSpanV);
    return 1.0 / (1.0 / (x + l.dead_length_v) + 1.0 / (kSensorSpanV - x + l.dead_length_v));
  };
  return l.coast_s * std::sqrt(compliance(x_v) / compliance(0.5 * kSensorSpanV));
}

void approach_observe(ApproachState& s, double y_v) noexcept {
  for (std::size_t i = s.readings.size() - 1; i > 0; --i) s.readings[i] = s.readings[i - 1];
  s.readings[0] = y_v;
  s.reading_count = std::min(s.reading_count + 1, s.readings.size());
}

double approach_speed_v_s(const ApproachState& s, double Ts) noexcept { return reading_slope(s, Ts); }

void approach_after_moving_reference(const ApproachLimits& l, ApproachState& s, double r_v, double y_v) noexcept {
  const double direction = r_v > y_v ? 1.0 : -1.0;
  if (direction * reading_slope(s, l.Ts) >= 0.5 * l.speed_v_s) {
    plan(l, s, r_v, y_v);     // straight in: it slides towards r
    s.retries = l.max_retries;  // one cut, then held wherever it stops
    return;
  }
  s.planned_r_v = r_v;
  s.final_direction = direction;
  s.next_direction = 0.0;  // a moving reference's arrival is where it stands, from where the piston is
  s.final_leg = true;
  s.short_approach = false;
  s.retries = l.max_retries;  // judged after the coast: held wherever it stopped
  s.cut_speed_v_s = 0.0;      // and nothing learned from it
  s.phase = ApproachPhase::kCoasting;
  s.samples_in_phase = 0;
}

ApproachOutput approach_step(const ApproachLimits& l, ApproachState& s, double r_v, double y_v) noexcept {
  approach_observe(s, y_v);

  ApproachOutput out;
  if (s.phase == ApproachPhase::kIdle || r_v != s.planned_r_v) {
    plan(l, s, r_v, y_v);
  } else if (s.phase == ApproachPhase::kCoasting && s.samples_in_phase >= l.settle_samples) {
    const double y_mean = mean_reading(s);
    const double error = s.planned_r_v - y_mean;
    if (s.final_leg && !s.short_approach && s.cut_speed_v_s >= 0.5 * l.speed_v_s && s.cut_speed_v_s <= 1.5 * l.speed_v_s) {
      // A stop off by e after a steady slide at v asks for a coast longer by e / v, by at most the
      // model's coast per stop (a cut in a breakaway, or a loop that stalled, must not teach it a
      // coast it then keeps); the offset follows at kLearningMemory's gain, within -3/4 to 3 times it.
      const std::size_t d = direction_index(s.final_direction);
      const double correction_s = s.final_direction * (y_mean - s.planned_r_v) / s.cut_speed_v_s;
      const double step_limit_s = l.coast_s;
      const double gain = 1.0 / static_cast<double>(std::min<int>(s.learned_stops[d] + 1, kLearningMemory));
      s.learned_offset_s[d] = std::clamp(s.learned_offset_s[d] + gain * std::clamp(correction_s, -step_limit_s, step_limit_s),
                                         -0.75 * l.coast_s, 3.0 * l.coast_s);
      ++s.learned_stops[d];
    }
    if (!s.final_leg) {
      start_leg(l, s, s.planned_r_v, s.final_direction, true, y_mean);
    } else if (std::abs(error) <= (s.short_approach ? std::max(l.retry_band_v, l.short_approach_band_v) : l.retry_band_v) ||
               s.retries >= l.max_retries) {
      hold(s, y_mean);
    } else {
      ++s.retries;
      back_off(l, s, y_mean);
    }
  } else if (s.phase == ApproachPhase::kHolding && s.reading_count >= s.readings.size() &&
             std::abs(mean_reading(s) - s.held_at_v) > 4.0 * l.retry_band_v) {
    plan(l, s, s.planned_r_v, mean_reading(s));  // pushed away from where it held: approach again
  }
  ++s.samples_in_phase;

  if (s.phase != ApproachPhase::kLeg) {
    out.w_v = y_v;
    out.hold = true;
    return out;
  }
  out.leg_started = s.samples_in_phase == 1;

  // The cut: the piston's predicted stop has reached the leg's target.
  const double dir = s.leg_direction;
  const double speed_towards = std::max(0.0, dir * reading_slope(s, l.Ts));
  const double to_go_v = dir * (s.leg_target_v - y_v) - speed_towards * s.leg_coast_s;  // predicted stop to target
  if (s.samples_in_phase > 1 && to_go_v <= 0.0) {
    s.cut_speed_v_s = s.final_leg ? speed_towards : 0.0;
    s.phase = ApproachPhase::kCoasting;
    s.samples_in_phase = 0;
    out.w_v = y_v;
    out.hold = true;
    return out;
  }

  // The path: cruise, brake gently to the approach speed over the last length_v, then go on at it
  // (at most one approach length past the target, should the piston lag that far).
  // Braking reads the nearer of the path and the piston: a piston that runs ahead of the path (a
  // plant faster than its model) still arrives at the approach speed.
  const double left_v = std::min(dir * (s.leg_target_v - s.path_v), dir * (s.leg_target_v - y_v));
  out.speed_v_s = dir * s.path_speed_v_s;  // before this sample's change: a leg's history runs at it
  const double top = dir > 0.0 ? l.top_speed_pos_v_s : l.top_speed_neg_v_s;
  const double scheduled =
      left_v < -l.length_v ? 0.0
                           : std::min(std::max(top, l.speed_v_s),
                                      std::sqrt(l.speed_v_s * l.speed_v_s + 2.0 * l.decel_v_s2 * std::max(0.0, left_v - l.length_v)));
  const double accel = s.short_approach && l.short_approach_accel_v_s2 > 0.0 ? l.short_approach_accel_v_s2 : l.accel_v_s2;
  s.path_speed_v_s = scheduled > s.path_speed_v_s ? std::min(scheduled, s.path_speed_v_s + accel * l.Ts)
                                                  : std::max(scheduled, s.path_speed_v_s - l.decel_v_s2 * l.Ts);
  s.path_v += dir * s.path_speed_v_s * l.Ts;
  out.w_v = s.path_v;
  const double per_sample_v = speed_towards * l.Ts;
  if (s.samples_in_phase > 1 && per_sample_v > 0.0 && to_go_v < per_sample_v) out.drive_fraction = to_go_v / per_sample_v;
  return out;
}

}  // namespace epa::control
