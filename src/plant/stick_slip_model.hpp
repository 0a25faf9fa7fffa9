#pragma once
// A reduced model of a pneumatic axis for identification: few parameters, each in
// physical units, and the two things a Hammerstein model cannot hold. Per unit of moving mass:
//
//   valve       s' = (u(k - delay) - s) / spool_lag_s         the spool follows the command
//   flow        w = speed_right (s - break_right)  for s > break_right
//                   speed_left  (s - break_left)   for s < break_left,   0 in between
//   air spring  z' = w - v                                     z: the spring's wind-up, mm
//   piston      v' = omega^2 (z - coulomb_mm sgn v) - 2 zeta omega v
//   stiction    a piston at rest stays at rest while |z| <= static_mm
//
// Why this form. The valve sets how fast the piston should go (w, mm/s); the chambers are an air
// spring between that and how fast it goes (v), so z integrates the difference. While the piston
// is stuck, z keeps whatever the last move left in the chambers: how soon the next pulse moves the
// piston depends on it (a reversal must first unwind it past -static_mm), which is the memory a
// Hammerstein model lacks. A breakaway releases static_mm - coulomb_mm of stored wind-up: the jump.
// Friction in mm of wind-up (force / air-spring stiffness) keeps every parameter readable without
// knowing the mass or the stiffness; omega is the air spring's natural frequency against the mass.
//
// Integration: `substeps` semi-implicit Euler steps per sample; a velocity reversal within a
// sub-step ends at v = 0, where the stiction test decides. Timing as the plants: step(u) holds
// u(k) over one sample and returns the position at k + 1.
#include <array>
#include <cstddef>
#include <string>

#include "core/model_file.hpp"
#include "core/result.hpp"
#include "core/stick_slip_params.hpp"

namespace epa::plant {

using core::StickSlipParams;


class StickSlipModel {
 public:
  static constexpr double kMaxStiffnessPerStep = 1.0;  // omega h and 2 zeta omega h, h = Ts / substeps
  // Errors: invalid params (validate), Ts <= 0, substeps outside 1..64, a spring or damping too
  // stiff for the sub-step (kMaxStiffnessPerStep).
  static core::Result<StickSlipModel> make(const StickSlipParams& params, double Ts, int substeps = 2);

  // At rest at position_mm with the spring unwound, the spool centred and no command in the delay line.
  void reset(double position_mm) noexcept;
  // Applies u(k) (V; non-finite is 0 V) and returns the position at k + 1, mm. Allocates nothing.
  double step(double valve_v) noexcept;

  // The piston held at position_mm at rest (an end stop); the spring keeps its wind-up.
  void stop_at(double position_mm) noexcept {
    y_mm_ = position_mm;
    v_mm_s_ = 0.0;
    stuck_ = true;
  }
  double position_mm() const noexcept { return y_mm_; }
  double speed_mm_s() const noexcept { return v_mm_s_; }
  double windup_mm() const noexcept { return z_mm_; }
  bool stuck() const noexcept { return stuck_; }
  const StickSlipParams& params() const noexcept { return p_; }

 private:
  StickSlipModel(const StickSlipParams& params, double Ts, int substeps);

  StickSlipParams p_;
  double h_s_ = 0.0;       // sub-step
  int substeps_ = 2;
  double spool_gain_ = 1.0;  // h / (lag + h): the spool's share of the gap per sub-step
  double omega2_ = 0.0, two_zeta_omega_ = 0.0;
  std::array<double, StickSlipParams::kMaxDelay + 1> delay_line_{};
  std::size_t delay_head_ = 0;
  double spool_v_ = 0.0, z_mm_ = 0.0, v_mm_s_ = 0.0, y_mm_ = 0.0;
  bool stuck_ = true;
};

// The command (V) at which the model's piston, at rest with the spring unwound, has moved
// travel_mm on a ramp of ramp_v_per_s towards `direction` (+1 or -1): its break point as a slow
// ramp reads it (flow dead zone plus the wind-up static friction needs). NaN when it never moves
// within 10 V.
double ramp_start_v(const StickSlipParams& params, double Ts, double ramp_v_per_s, double direction,
                    double travel_mm = 0.5);

// How long the model's piston, sliding steadily at speed_mm_s, goes on after the valve is centred:
// coast distance / speed (s), the mean of both directions (pp-traj's coast_s, control/
// sliding_approach.hpp). The speed is read as that law reads it, the least-squares slope of the last
// 4 positions, after 1 s at the command that gives it. NaN when neither direction slides.
double coast_time_s(const StickSlipParams& params, double Ts, double speed_mm_s);

// pp-traj's coast_s for the axis a model file describes: coast_time_s of its [stick_slip] model at
// approach_speed_mm_s when the file says that model describes the axis (axis_model, epa identify's
// verdict: on such an axis a stop cannot be corrected from rest by less than a breakaway jump, so
// the law arrives while sliding), else 0 (off: the integrator corrects). Error: the stick-slip
// model does not slide at that speed (no coast to give).
core::Result<double> sliding_arrival_coast_s(const core::ModelFile& file, double approach_speed_mm_s);

}  // namespace epa::plant
