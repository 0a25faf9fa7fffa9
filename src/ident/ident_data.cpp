#include "ident/ident_data.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"

namespace epa::ident {

using core::format_number;

std::vector<Segment> split_run(const core::Run& run, const std::string& name, const SegmentOptions& o,
                               SegmentReport* report) {
  std::vector<Segment> segments;
  SegmentReport r;
  const std::size_t n = std::min({run.t_s.size(), run.y_mm.size(), run.u_V.size()});
  auto at_stop = [&](std::size_t k) {
    return run.y_mm[k] <= o.end_margin_mm || run.y_mm[k] >= o.stroke_mm - o.end_margin_mm;
  };
  std::size_t k = 0;
  while (k < n) {
    if (at_stop(k)) {
      ++r.samples_at_stops;
      ++k;
      continue;
    }
    std::size_t end = k;
    while (end < n && !at_stop(end)) ++end;
    if (end - k < o.min_segment) {
      r.samples_in_short += end - k;
    } else {
      Segment s;
      s.t0_s = run.t_s[k];
      s.name = (k == 0 && end == n) ? name
                                    : name + " [t " + format_number(run.t_s[k]) + "-" + format_number(run.t_s[end - 1]) + " s]";
      s.y.reserve(end - k);
      s.u.reserve(end - k);
      for (std::size_t i = k; i < end; ++i) {
        s.y.push_back(run.y_mm[i] / o.mm_per_volt);
        s.u.push_back(run.u_V[i]);
      }
      segments.push_back(std::move(s));
    }
    k = end;
  }
  if (report) *report = r;
  return segments;
}

std::size_t total_samples(const std::vector<Segment>& segments) {
  std::size_t n = 0;
  for (const auto& s : segments) n += s.size();
  return n;
}

core::Status check_excitation(const std::vector<Segment>& segments, const std::string& run_name,
                              const ExcitationCheck& c, double mm_per_volt) {
  const std::size_t n = total_samples(segments);
  if (n < c.min_samples)
    return core::invalid_argument(
        run_name + ": " + std::to_string(n) + " usable samples (away from the end stops), identification needs at least " +
        std::to_string(c.min_samples) + ": record a longer run (epa excite --duration), or keep the piston off the stops");
  double u_min = INFINITY, u_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
  for (const auto& s : segments) {
    for (double u : s.u) u_min = std::min(u_min, u), u_max = std::max(u_max, u);
    for (double y : s.y) y_min = std::min(y_min, y), y_max = std::max(y_max, y);
  }
  if (!(u_max - u_min >= c.min_input_span_v))
    return core::invalid_argument(run_name + ": the valve command only spans [" + format_number(u_min) + ", " +
                                  format_number(u_max) + "] V, so it does not excite the plant: drive the valve with "
                                  "pulses through and beyond the dead band (epa excite)");
  const double motion_mm = (y_max - y_min) * mm_per_volt;
  if (!(motion_mm >= c.min_motion_mm))
    return core::invalid_argument(run_name + ": the piston moves only " + format_number(motion_mm) + " mm (at least " +
                                  format_number(c.min_motion_mm) + " mm needed): the valve command (up to " +
                                  format_number(std::max(std::abs(u_min), std::abs(u_max))) +
                                  " V) probably never leaves the dead band; use larger pulses (epa excite --amplitude-max)");
  if (c.need_both_directions && !(u_min < 0.0 && u_max > 0.0))
    return core::invalid_argument(run_name + ": the valve command stays " + (u_max <= 0.0 ? "<= 0" : ">= 0") +
                                  " V, so one side of the dead zone (slope and break point) cannot be identified: "
                                  "drive the valve both ways");
  return core::ok();
}

}  // namespace epa::ident
