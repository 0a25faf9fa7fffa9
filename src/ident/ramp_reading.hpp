#pragma once
// The dead band read off the slow ramps of an excitation run (excitation.hpp, phase 1; the paper's
// figure 6): where the piston starts to move from rest while the command rises, and where the
// moving piston stops while the command falls back.
//
// A static dead zone cannot hold the difference between the two. A real valve and cylinder need
// more command to break the piston away from rest (static friction, and the chamber must fill
// before the force exceeds it) than to keep it moving (sliding friction): on the ramp back the
// piston keeps moving down to a smaller command. Any break point between the two explains the
// ramp in some way, and none outside does: a smaller one would move the piston where it stood
// still on the way back, a larger one would leave it at rest where it started to move. So the two
// readings bound each break point, and the simulation-error fit (output_error_fit.hpp) chooses
// within that band.
//
// On a Hammerstein plant both readings sit just beyond the break point (the piston must travel
// `motion_mm` within `motion_window_s` to count as moving), the stop reading slightly on the
// dead band's side of it: the band holds the break point with a few hundredths of a volt to spare.
//
// A ramp is a run of samples over which the command changes by at most `max_ramp_step_v` per sample,
// leaving 0 V and first rising in magnitude (for at least `min_ramp_s`), then possibly falling
// back. Pulses (steps) are never ramps.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "ident/ident_data.hpp"
#include "ident/output_error_fit.hpp"

namespace epa::ident {

struct RampReadingOptions {
  double Ts = 0.005;              // s
  double mm_per_volt = 50.0;      // segments hold y in sensor volts
  double max_ramp_step_v = 0.05;  // per sample: 10 V/s at 5 ms, far slower than a pulse's step
  double min_ramp_s = 0.5;        // the rising part must last this long
  double motion_mm = 0.5;         // the piston moves once it travels this far ...
  double motion_window_s = 0.1;   // ... within this time, in the ramp's direction (not creep, not noise)
  std::size_t smoothing = 4;      // samples averaged against sensor noise

  core::Status validate() const;  // messages name the field
};

struct RampReading {
  std::string segment;   // the segment's name
  double t_s = 0.0;      // start of the ramp, from the segment's start
  int direction = 1;     // +1: towards +, -1: towards -
  double peak_v = 0.0;   // the command the ramp reached
  double start_v = 0.0;  // command when the piston started to move on the way out; NaN: it never did
  double stop_v = 0.0;   // command when it last moved on the way back; NaN: no way back, or it never moved
};

struct DeadBandReading {
  std::vector<RampReading> ramps;
  // The band each break point must lie in: [smallest stop, largest start] in magnitude over that
  // side's ramps; only an upper bound (the start) when no ramp back was seen; none without a ramp
  // that moved the piston.
  std::optional<BreakPointRange> right, left;
};

// Errors: invalid options. Segments without ramps give an empty reading.
core::Result<DeadBandReading> read_dead_band(const std::vector<Segment>& segments, const RampReadingOptions& options);

}  // namespace epa::ident
