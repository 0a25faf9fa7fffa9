#pragma once
// A limit cycle about a standing target, and the hold that ends it. A law with integral action on
// an axis whose friction it does not model hunts: the piston sticks short of the target, the drive
// grows until it breaks away, the piston jumps past, sticks on the other side, and the same again
// (pp-traj on the physics plant with the paper's model: about +-6 mm about the target, 1.5 s a
// cycle, for ever). A positioning controller must not sit in such a cycle, so every law is watched
// while its target stands, from the first time the piston reaches it (comes within side_band_v, or
// passes it: the rest it started from is no side of a cycle): the piston comes to rest (its
// readings within rest_band_v for rest_samples) farther than side_band_v from the target, on the
// other side than its last rest; rest_reversals such rests within window_samples are a limit cycle. A slow smooth oscillation
// counts too, its peaks dwelling like rests. The valve is then held centred (0 V, inside the dead
// band: the piston stays where it stands) until the target changes or a move to it starts again
// (controller_new_move), and the law's output says so.
// Not watched: crossings of the target as such. The printed model swings its output tens of
// millimetres a sample (docs/paper.md) and crosses its target several times in a move that then
// settles; a rest there lasts a sample or two. A move that overshoots once and comes back changes
// side once; the next target starts the watch afresh.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace epa::control {

struct HuntingLimits {
  double rest_band_v = 0.01;           // 0.5 mm at 50 mm/V: well above 0.1 mm of sensor noise, far below a stick-slip jump
  std::uint32_t rest_samples = 10;     // 50 ms at Ts = 5 ms
  double side_band_v = 0.01;           // within this of the target the piston is on it, on neither side
  std::uint32_t window_samples = 400;  // 2 s at Ts = 5 ms
  int rest_reversals = 2;
};

// The limits for a sample period: rests of 50 ms, a window of 2 s.
HuntingLimits hunting_limits_for(double Ts) noexcept;

struct HuntingState {
  static constexpr std::size_t kEvents = 8;  // >= rest_reversals
  double target_v = NAN;          // the standing target watched; NaN: none yet
  std::uint32_t sample = 0;       // samples since the target was set
  int start_side = 0;             // where the piston was when the target was set (as last_rest_side)
  bool reached = false;           // the piston has reached the target since: rests count from then on
  double rest_anchor_v = 0.0;     // where the current stillness began
  std::uint32_t still_samples = 0;
  bool rest_counted = false;      // the current rest's side has been taken
  int last_rest_side = 0;         // -1 below the target, +1 above it, 0 none yet
  std::array<std::uint32_t, kEvents> reversals_at{};  // sample numbers of the reversals, a ring
  std::size_t reversals = 0;                          // noted so far
  bool hunting = false;           // latched until the target changes (or the state is reset)
};

// One sample: the standing target r(k) and the reading y(k), in sensor volts. True while the valve
// must be held centred.
bool hunting_step(const HuntingLimits& limits, HuntingState& state, double r_v, double y_v) noexcept;

}  // namespace epa::control
