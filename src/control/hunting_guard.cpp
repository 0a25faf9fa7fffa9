#include "control/hunting_guard.hpp"

#include <algorithm>

namespace epa::control {

namespace {

int side_of(double y_v, double r_v, double band_v) noexcept {
  if (y_v > r_v + band_v) return 1;
  if (y_v < r_v - band_v) return -1;
  return 0;
}

void note(std::array<std::uint32_t, HuntingState::kEvents>& ring, std::size_t& count, std::uint32_t sample) noexcept {
  ring[count % ring.size()] = sample;
  ++count;
}

// How many of the last noted events lie within `window` samples of `now`.
int within(const std::array<std::uint32_t, HuntingState::kEvents>& ring, std::size_t count, std::uint32_t now,
           std::uint32_t window) noexcept {
  int n = 0;
  for (std::size_t i = 0; i < std::min(count, ring.size()); ++i)
    if (now - ring[(count - 1 - i) % ring.size()] <= window) ++n;
  return n;
}

}  // namespace

HuntingLimits hunting_limits_for(double Ts) noexcept {
  HuntingLimits l;
  if (Ts > 0.0 && std::isfinite(Ts)) {
    l.rest_samples = static_cast<std::uint32_t>(std::max(1.0, std::round(0.05 / Ts)));
    l.window_samples = static_cast<std::uint32_t>(std::max(1.0, std::round(2.0 / Ts)));
  }
  return l;
}

bool hunting_step(const HuntingLimits& l, HuntingState& s, double r_v, double y_v) noexcept {
  if (!(r_v == s.target_v)) {  // a new target (or the first): watch afresh
    s = {};
    s.target_v = r_v;
    s.rest_anchor_v = y_v;
    s.start_side = side_of(y_v, r_v, l.side_band_v);
  }
  if (s.hunting) return true;
  ++s.sample;
  if (!s.reached) {
    const int side = side_of(y_v, r_v, l.side_band_v);
    s.reached = side == 0 || side != s.start_side;
    if (!s.reached) return false;
    s.rest_anchor_v = y_v, s.still_samples = 0;  // rests count from here
  }

  if (std::abs(y_v - s.rest_anchor_v) > l.rest_band_v) {
    s.rest_anchor_v = y_v, s.still_samples = 0, s.rest_counted = false;
  } else if (++s.still_samples >= l.rest_samples && !s.rest_counted) {
    s.rest_counted = true;
    if (const int side = side_of(s.rest_anchor_v, r_v, l.side_band_v); side != 0) {
      if (s.last_rest_side != 0 && side != s.last_rest_side) note(s.reversals_at, s.reversals, s.sample);
      s.last_rest_side = side;
    }
  }
  s.hunting = within(s.reversals_at, s.reversals, s.sample, l.window_samples) >= l.rest_reversals;
  return s.hunting;
}

}  // namespace epa::control
