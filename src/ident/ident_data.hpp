#pragma once
// Identification data: runs (epa-run/1) turned into segments of uniformly sampled (y, u) in the
// model's units, with the checks that tell a user why a run cannot identify anything.
//
// Units: y in sensor volts (y_mm / mm_per_volt, as the model's A y = B u_d), u in valve volts.
// Timing (core/run.hpp): row k holds y(k) and the u(k) applied from k to k+1, so y(k) depends on
// u(k-1), u(k-2), ... (nk >= 1).
//
// End stops: a piston held at a stroke end does not follow the linear model. Samples within
// `end_margin_mm` of either end are dropped and the run is split there, so no regression row
// spans a stop; each piece is its own segment (no regressor ever crosses a segment boundary).
#include <cstddef>
#include <string>
#include <vector>

#include "core/result.hpp"
#include "core/run.hpp"

namespace epa::ident {

struct Segment {
  std::string name;      // "runs/a.csv" or "runs/a.csv [t 12.3-40.1 s]" for a piece of a run
  double t0_s = 0.0;     // time of the first sample, s
  std::vector<double> y; // position, sensor V
  std::vector<double> u; // valve command, V (or the dead-zone output u_d once transformed)

  std::size_t size() const { return y.size(); }
};

struct SegmentOptions {
  double mm_per_volt = 50.0;     // sensor scale of the model
  double stroke_mm = 500.0;      // end stops at 0 and stroke_mm
  double end_margin_mm = 1.0;    // samples this close to an end count as "at the stop"
  std::size_t min_segment = 50;  // shorter pieces between stops are dropped
};

struct SegmentReport {
  std::size_t samples_at_stops = 0;  // dropped because the piston was at an end stop
  std::size_t samples_in_short = 0;  // dropped because their piece was shorter than min_segment
};

// Splits `run` into segments (see above). `name` is used in segment names and messages.
std::vector<Segment> split_run(const core::Run& run, const std::string& name, const SegmentOptions& options,
                               SegmentReport* report = nullptr);

struct ExcitationCheck {
  std::size_t min_samples = 400;      // per run, after dropping end-stop samples (2 s at 5 ms)
  double min_motion_mm = 5.0;         // the piston must move at least this much (max - min)
  double min_input_span_v = 0.5;      // the valve command must span at least this much
  bool need_both_directions = true;   // the dead zone has two sides: u must go both ways
};

// Refuses segments that cannot identify the plant, with a message naming the run and what to do:
// too few samples, a valve command that never changes, a piston that never moves, a valve that is
// never driven to both sides (the left/right slope and break point would be unidentifiable).
core::Status check_excitation(const std::vector<Segment>& segments, const std::string& run_name,
                              const ExcitationCheck& check, double mm_per_volt);

// Total number of samples over all segments.
std::size_t total_samples(const std::vector<Segment>& segments);

}  // namespace epa::ident
