#pragma once
// The four position controllers as pure control laws: validated immutable ControllerParams,
// explicit ControllerState, and controller_step() which allocates nothing, reads no clock and does
// no I/O. All signals are in the model's units: reference and position in sensor volts, valve in V.
#include "control/controller_kind.hpp"
#include "control/hunting_guard.hpp"
#include "control/rst_law.hpp"
#include "control/trajectory_law.hpp"
#include "core/dead_zone.hpp"
#include "core/polynomial.hpp"
#include "core/result.hpp"

namespace epa::control {

// What a user or a file provides; checked by ControllerParams::make.
struct ControllerConfig {
  ControllerKind kind = ControllerKind::kPpFfidz;
  core::Polynomial F, G, H;  // H empty: H = G (error feedback, docs/paper.md)
  core::DeadZone dead_zone;  // what NG-IDZ and FF-IDZ invert
  double lc_v = 0.1;         // FF-IDZ switch-off band l_c, sensor volts (5 mm at 50 mm/V)
  double valve_limit_v = 5.0;  // final valve command saturates at +-limit (paper section 4.1)
  double safe_valve_v = 0.0;   // command on a fault (non-finite input): 5/3 valve centred
  // pp-traj: the model it computes its feed-forward from, its sample period and its own
  // parameters (trajectory_law.hpp); the other laws ignore them but Ts, which sets the hunting
  // watch's rests and window (hunting_guard.hpp).
  core::Polynomial A, B;
  double Ts = 0.005;
  TrajectoryConfig trajectory;
};

class ControllerParams {
 public:
  // A default-constructed ControllerParams is the zero controller (u = 0, valve at 0 V): a safe
  // placeholder in fixed-size storage. Real parameters come only from make().
  ControllerParams() = default;
  // Errors name what is wrong: non-monic F, an order above kMaxLawOrder, a non-finite coefficient
  // (with its index), a non-positive slope, b_l > b_r, a negative l_c, a bad limit.
  static core::Result<ControllerParams> make(const ControllerConfig& config);

  ControllerKind kind() const { return kind_; }
  const RstCoefficients& rst() const { return rst_; }
  const core::DeadZone& dead_zone() const { return dead_zone_; }
  double lc_v() const { return lc_v_; }
  double valve_limit_v() const { return valve_limit_v_; }
  double safe_valve_v() const { return safe_valve_v_; }
  const TrajectoryParams& trajectory() const { return trajectory_; }
  const TrajectoryConfig& trajectory_config() const { return trajectory_config_; }  // what pp-traj was made from
  const HuntingLimits& hunting() const { return hunting_; }
  // pp-traj's arrival while sliding re-approaches a target at most max_retries times, from either
  // side: bounded by itself, and not to be taken for a limit cycle.
  bool watched_for_hunting() const { return !(kind_ == ControllerKind::kPpTraj && trajectory_.sliding_approach); }

 private:
  ControllerKind kind_ = ControllerKind::kPp;
  RstCoefficients rst_;
  core::DeadZone dead_zone_;
  double lc_v_ = 0.0, valve_limit_v_ = 5.0, safe_valve_v_ = 0.0;
  TrajectoryParams trajectory_;
  TrajectoryConfig trajectory_config_;
  HuntingLimits hunting_;
};

// A default-constructed state is "not started": pp-traj starts its profile at the first y it reads.
struct ControllerState {
  RstState rst;
  TrajectoryState trajectory;
  HuntingState hunting;
  int saturated_sign = 0;  // sign of the last command's saturation, 0: not saturated (anti-windup)
};

struct ControllerOutput {
  double valve_v = 0.0;       // command for the valve, after compensation and saturation
  double controller_v = 0.0;  // pole-placement output u before compensation (uc_V in run files)
  bool saturated = false;     // the valve command hit its limit
  bool fault = false;         // non-finite input or output: valve_v is the safe command, state kept
  bool hunting = false;       // a limit cycle about the standing target: the valve is held at 0 V until the target changes
  // pp-traj hunted: from this sample on it arrives while sliding (trajectory_fall_back_to_sliding)
  bool sliding_fallback_started = false;
};

// Starts a law on a piston at y_v moving at speed_v_s (V/s), as when RUN begins or another law
// hands over: the RST laws with no error or output history, pp-traj with its profile there.
void controller_start(const ControllerParams& params, ControllerState& state, double y_v, double speed_v_s) noexcept;

// A move starts, to a new target or the same one again: the hunting watch forgets the last move
// and releases its hold (the next target releases it too, by itself). approach_direction: the side
// pp-traj's sliding arrival comes from (+1 below, -1 above; a position record's), 0: the near side.
inline void controller_new_move(ControllerState& state, double approach_direction = 0.0) noexcept {
  state.hunting = {};
  state.trajectory.approach.next_direction = approach_direction;
  if (approach_direction != 0.0) state.trajectory.approach.phase = ApproachPhase::kIdle;  // planned afresh, even to the same target
}

// One sample: reads r(k), y(k) (sensor volts), returns the valve command to hold until k+1.
// No anti-windup: the paper's law runs on the unsaturated u (its F has no pole at 1). Every law
// but pp-traj's sliding arrival is watched for hunting (hunting_guard.hpp). The RST laws are then
// held, and keep running under the hold, so they take the next target from where they stand;
// pp-traj falls back to arriving while sliding, whose retries are bounded.
ControllerOutput controller_step(const ControllerParams& params, ControllerState& state, double r_v,
                                 double y_v) noexcept;

}  // namespace epa::control
