#pragma once
// The settings of the appliance's excitation experiment (mode EXCITE): the `[excite]` section of
// the configuration, and the excite_* points an unlocked client may change. A change takes effect
// the next time EXCITE is entered; a running experiment keeps the settings it started with.
//
// The signal is ident::ExcitationGenerator's (slow ramps through the dead band, then multi-level
// pseudo-random pulses), run in soft-limit coordinates (runtime/excitation_run.hpp): its "stroke"
// is the span between the soft limits and its guard lines lie `guard_mm` inside them, so every
// pulse heading for a soft limit is cut before the piston gets there, whatever the stroke.
#include <cstdint>

namespace epa::runtime {

struct RuntimeConfig;

struct ExcitationSettings {
  std::uint32_t seed = 1;         // the pulses' pseudo-random sequence: a seed gives the same signal
  double amplitude_min_v = 0.2;   // smallest pulse level, V (inside the dead band on purpose)
  double amplitude_max_v = 3.0;   // largest |valve command| of ramps and pulses, V
  double duration_s = 50.0;       // the whole experiment; then STOP by itself
  double guard_mm = 100.0;        // pulses towards a soft limit end this far inside it
  bool sweep = true;              // pulse signs cross the span (ident::ExcitationOptions::sweep)
};

// The recorder must still hold the experiment's first sample when its last is written: its ring
// keeps at least the configured experiment and this much more (the recorder thread picks a request
// up within 20 ms; a second leaves room for a loaded machine).
inline constexpr double kExcitationRecorderSlackS = 1.0;

// The longest experiment the recorder's ring keeps whole with `config`: the configured one, or
// longer when [recorder] buffer_s holds more.
double max_excitation_duration_s(const RuntimeConfig& config) noexcept;

// Whether an experiment may start with the piston at `position_mm`: between the guard lines, so
// the ramps, which no guard cuts, have room on both sides.
bool excitation_may_start_at(double position_mm, const ExcitationSettings& s, const RuntimeConfig& config) noexcept;

// The first rule `s` breaks with `config` (its soft limits, period and recorder buffer), as a
// sentence naming the setting; nullptr when it breaks none. Static text and no allocation: the
// scan cycle checks commands with it. Settings it accepts always make a valid generator.
const char* excitation_problem(const ExcitationSettings& s, const RuntimeConfig& config) noexcept;

}  // namespace epa::runtime
