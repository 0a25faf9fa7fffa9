#include "ident/ramp_reading.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"

namespace epa::ident {

namespace {

using core::format_number;

// One segment's ramps.
void read_segment(const Segment& s, const RampReadingOptions& o, std::vector<RampReading>& out) {
  const std::size_t n = s.size();
  const auto window = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(o.motion_window_s / o.Ts)));
  const std::size_t smooth = std::max<std::size_t>(1, o.smoothing);
  const auto min_rising = static_cast<std::size_t>(std::llround(o.min_ramp_s / o.Ts));
  auto mean_mm = [&](std::size_t k) {
    double sum = 0.0;
    for (std::size_t i = 0; i < smooth; ++i) sum += s.y[k - i];
    return sum / static_cast<double>(smooth) * o.mm_per_volt;
  };
  // Travel in direction d over the last `window` samples (0 before there is enough history).
  auto motion_mm = [&](std::size_t k, double d) {
    return k + 1 >= window + smooth ? d * (mean_mm(k) - mean_mm(k - window)) : 0.0;
  };
  auto slow_step = [&](std::size_t k) { return std::abs(s.u[k] - (k == 0 ? 0.0 : s.u[k - 1])) <= o.max_ramp_step_v; };

  std::size_t k = 0;
  while (k < n) {
    const bool leaves_zero = (k == 0 || s.u[k - 1] == 0.0) && s.u[k] != 0.0 && slow_step(k);
    if (!leaves_zero) {
      ++k;
      continue;
    }
    const double d = s.u[k] > 0.0 ? 1.0 : -1.0;
    RampReading r{s.name, static_cast<double>(k) * o.Ts, static_cast<int>(d), s.u[k], NAN, NAN};
    bool rising = true, moved_back = false;
    std::size_t rising_samples = 1, j = k + 1;
    for (; j < n && d * s.u[j] > 0.0 && slow_step(j); ++j) {
      const bool up = std::abs(s.u[j]) >= std::abs(s.u[j - 1]);
      if (!rising && up) break;  // rising again: not this ramp's way back any more
      rising = rising && up;
      const bool moving = motion_mm(j, d) >= o.motion_mm;
      if (rising) {
        ++rising_samples;
        r.peak_v = s.u[j];
        if (moving && std::isnan(r.start_v)) r.start_v = s.u[j];
      } else if (moving) {
        r.stop_v = s.u[j];
        moved_back = true;
      }
    }
    if (rising_samples >= min_rising) {
      // Motion seen only after the turn: the valve was open at the peak at the latest.
      if (std::isnan(r.start_v) && moved_back) r.start_v = r.peak_v;
      out.push_back(r);
    }
    k = std::max(j, k + 1);
  }
}

}  // namespace

core::Status RampReadingOptions::validate() const {
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(Ts)) return core::invalid_argument("ramp reading: Ts must be > 0 s, got " + format_number(Ts));
  if (!positive(mm_per_volt))
    return core::invalid_argument("ramp reading: the sensor scale must be > 0 mm/V, got " + format_number(mm_per_volt));
  if (!positive(max_ramp_step_v))
    return core::invalid_argument("ramp reading: the largest ramp step must be > 0 V, got " + format_number(max_ramp_step_v));
  if (!(min_ramp_s >= 0.0 && std::isfinite(min_ramp_s)))
    return core::invalid_argument("ramp reading: the shortest ramp must be >= 0 s, got " + format_number(min_ramp_s));
  if (!positive(motion_mm)) return core::invalid_argument("ramp reading: the motion threshold must be > 0 mm, got " + format_number(motion_mm));
  if (!positive(motion_window_s))
    return core::invalid_argument("ramp reading: the motion window must be > 0 s, got " + format_number(motion_window_s));
  return core::ok();
}

core::Result<DeadBandReading> read_dead_band(const std::vector<Segment>& segments, const RampReadingOptions& o) {
  if (auto s = o.validate(); !s) return s.error();
  DeadBandReading reading;
  for (const auto& s : segments) read_segment(s, o, reading.ramps);
  // Per side, in magnitude: the band [smallest stop, largest start].
  for (const int side : {1, -1}) {
    double start = NAN, stop = NAN;
    for (const auto& r : reading.ramps) {
      if (r.direction != side || std::isnan(r.start_v)) continue;
      start = std::isnan(start) ? std::abs(r.start_v) : std::max(start, std::abs(r.start_v));
      if (!std::isnan(r.stop_v)) stop = std::isnan(stop) ? std::abs(r.stop_v) : std::min(stop, std::abs(r.stop_v));
    }
    if (std::isnan(start)) continue;
    const double lo = std::isnan(stop) ? 0.0 : std::min(stop, start);
    if (side > 0) reading.right = BreakPointRange{lo, start};
    else reading.left = BreakPointRange{-start, -lo};
  }
  return reading;
}

}  // namespace epa::ident
