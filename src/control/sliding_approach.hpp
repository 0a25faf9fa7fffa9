#pragma once
// pp-traj's arrival on an axis with stick-slip (docs/paper.md, notes/stick-slip.md): arrive while
// sliding, never correct from rest by a small amount.
//
// Why. A stopped pneumatic piston cannot be moved by less than one breakaway jump (the chambers must
// build the static friction's force, which then throws the piston 5-10 mm); an integrator that
// corrects a stop 1-3 mm off therefore hunts. What can be placed precisely is the end of a steady
// slide: with the valve centred, the piston coasts for a time the air spring and the spool set
// (coast_s, from the identified stick-slip model: plant/stick_slip_model.hpp, coast_time_s). So:
//
//   leg      a path towards the leg's target at the law's top speed, braking gently (decel_v_s2,
//            slow against the air spring's period so that it does not ring) to a steady approach
//            speed over the last length_v, and on at that speed past the target if need be
//   cut      the valve is centred at the first sample where the predicted stop, y + v coast_s
//            (v: least-squares slope of the last 4 readings), reaches the target; in the sample
//            before, the drive is scaled to the share of the sample still to go, so the stop is
//            not quantised to the v Ts the piston covers per sample (+-0.3 mm at 120 mm/s)
//   judge    settle_samples later, the mean of the last 4 readings against the target: within
//            retry_band_v, hold; else back off length_v and approach again (at most max_retries).
//            A short approach (see short) is judged within short_approach_band_v when that is
//            wider: its retry would be as short, and no surer
//   where    the coast depends on where along the stroke the piston stops: the air spring that
//            brakes it stiffens near an end (coast_at_s below)
//   learn    every stop after a steady slide corrects the coast of its direction by its error /
//            the speed at the cut, and the next approach that way (a retry, or the next move's)
//            cuts with it: the model's coast is a first guess (on an axis the identification saw
//            through a slower I/O path it was 1-3 mm long); the correction is kept as an offset,
//            the same at every position, as a delay the model did not see would be, and the
//            offset is the running mean of what the stops asked for (over about the last 4), so
//            that a retry does not chase one stop's scatter. A short approach (below) teaches
//            nothing: it starts with a breakaway from rest at the end, and its stop says little
//            of a steady slide's coast
//   short    a move shorter than length_v backs off first (unless the piston already slides
//            towards the target), so that every final approach is a steady slide, not the
//            breakaway jump of a start from rest; near an end of [travel_min_v, travel_max_v]
//            (the loop's setpoint range) it backs off only as far as that end, or goes straight
//            in when the piston already stands there. Such a short approach (a final leg from
//            rest with less than length_v to go because the travel cuts it) speeds up at
//            short_approach_accel_v_s2. An approach never comes from the target's far side: a
//            gripper or a part may stand there
//   hold     the valve stays centred until the setpoint changes or the piston is pushed more than
//            4 retry bands from where it stopped
//
// The approach direction of a retry is the move's: unidirectional positioning, as machine tools do
// against backlash. Fixed storage, no allocation; positions in sensor volts.
#include <array>
#include <cstddef>

namespace epa::control {

struct ApproachLimits {
  double coast_s = 0.0;          // > 0, at mid-stroke
  double dead_length_v = 0.5;    // each chamber's dead volume (ports, tubing) as a length of stroke, V (> 0)
  double speed_v_s = 2.4;        // approach speed, V/s
  double length_v = 1.0;         // length of the final, steady approach, V
  double decel_v_s2 = 6.0;       // braking to the approach speed, V/s^2
  double top_speed_pos_v_s = 10.0, top_speed_neg_v_s = 10.0;  // the leg's cruise speed each way
  double accel_v_s2 = 100.0;     // speeding up
  // Speeding up on a short approach (see short), V/s^2 (0: accel_v_s2): slower, so that the chambers
  // build the breakaway's force gently and the piston does not leave the end in a burst.
  double short_approach_accel_v_s2 = 0.0;
  double retry_band_v = 0.006;   // judged within this, V
  // A stop after a short approach (less than length_v of steady slide: from rest near a travel end)
  // is judged within this when it is wider than retry_band_v, V: the next approach would be as short,
  // and scatters as much (0: no such allowance).
  double short_approach_band_v = 0.0;
  int max_retries = 3;
  std::size_t settle_samples = 30;  // from the cut to the judgement
  double Ts = 0.005;
  double travel_min_v = 0.0, travel_max_v = 10.0;  // back-off points stay within (the loop's setpoint range)
};

enum class ApproachPhase { kIdle, kLeg, kCoasting, kHolding };

struct ApproachState {
  ApproachPhase phase = ApproachPhase::kIdle;
  double planned_r_v = 0.0;    // the setpoint the legs were planned for
  double leg_target_v = 0.0;
  double leg_direction = 1.0;  // +1 / -1
  double final_direction = 1.0;  // the move's approach direction
  double next_direction = 0.0;   // +1 / -1: the next plan approaches this way (a move's side kept), 0: from where the piston is
  bool final_leg = false;
  bool short_approach = false;  // this final leg starts from rest with less than length_v to go, because the travel cuts it
  int retries = 0;
  double path_v = 0.0, path_speed_v_s = 0.0;  // the leg's reference and its speed (>= 0, along leg_direction)
  double leg_coast_s = 0.0;       // the coast this leg's cut assumes: at its target, plus the move's direction's offset
  std::array<double, 2> learned_offset_s{};  // upwards, downwards: what the stops so far add to the coast
  std::array<int, 2> learned_stops{};         // how many stops taught it, each way
  double cut_speed_v_s = 0.0;     // at the last cut of a final leg (0: not a steady slide)
  double held_at_v = 0.0;         // where the piston stopped, while holding
  std::size_t samples_in_phase = 0;
  std::array<double, 4> readings{};  // newest first
  std::size_t reading_count = 0;
};

struct ApproachOutput {
  double w_v = 0.0;          // the reference w(k)
  bool hold = false;         // valve centred
  bool leg_started = false;  // a leg starts here: the caller restarts its reference history and filters at w_v
  double speed_v_s = 0.0;    // the reference's speed before this sample, signed (at a leg's start: the speed its history ran at)
  double drive_fraction = 1.0;  // of the law's drive to apply (< 1 in the sample before a cut)
};

// The coast after a cut at x_v (sensor volts, the stroke's ends at 0 and 10 V), s: coast_s scaled
// by 1/omega of the air spring there against mid-stroke. With the valve centred, the chambers act
// as an air spring that brakes the piston; at force balance its stiffness goes with
// 1/(length of A) + 1/(length of B), each length counted with its chamber's dead volume, so it
// stiffens near an end and the coast shortens: on the physics plant from 23-24 ms at mid-stroke to
// 17 ms at 75 mm and 8 ms at 3 mm of 500. Given that plant's dead volumes, this form follows its
// coast within 6 % from 25 to 475 mm (PpTrajSliding.TheCoastAlongTheStrokeFollowsThePhysicsPlant).
// The dead length is a tuning parameter, not identified: the excitation keeps 100 mm from the ends,
// where it hardly matters (on that plant's first approaches 12.5 or 25 mm: within 0.36 or 0.24 mm).
// Why the whole coast scales, though the valve's dead time and spool lag are part of it: the physics
// plant's coast follows the pure form, and the split the stick-slip model fits (0.79 of it the
// spring's) missed its ends.
double coast_at_s(const ApproachLimits& limits, double x_v) noexcept;

// One sample. The first call (or any with the phase set to kIdle) plans from y_v.
ApproachOutput approach_step(const ApproachLimits& limits, ApproachState& state, double r_v, double y_v) noexcept;

// After a reference that moved (a halt's braking, a jog, a move with a speed limit) has come to
// stand at r: a piston still sliding towards r at half the approach speed or more is cut at its
// predicted stop, one that does not is let coast; either is then held where it stops, never
// backed off and approached again (a halt or a released jog must not set off a new move).
void approach_after_moving_reference(const ApproachLimits& limits, ApproachState& state, double r_v, double y_v) noexcept;

// Takes a reading without stepping (while another law follows the reference), so that a plan made
// later starts from the piston's speed.
void approach_observe(ApproachState& state, double y_v) noexcept;
// The piston's speed from the last readings, V/s (least-squares slope of 4; 0 until there are 4).
double approach_speed_v_s(const ApproachState& state, double Ts) noexcept;

}  // namespace epa::control
