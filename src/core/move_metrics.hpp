#pragma once
// The metrics of one move of the axis, over its own samples and against its target. The loop's
// registers, the status page, the store's run history and a recomputation from the move's run
// file all come from this one function, so they agree.
//
// A move starts when a target is set in RUN and lasts until it ends (MoveEnd). Its samples are
// the positions read from its first cycle to its last. Metrics that do not apply to how it ended
// are NaN ("n/a"), never a number:
// A move was let to end when it ended in position, off target or judged (timeout); one cut short,
// halted, stopped, faulted or switched to another law was not.
//   rise_s        10 % to 90 % of the way from `from` to the target; NaN: 90 % never reached
//   overshoot_pct furthest travel beyond the target, % of the move; NaN: halted, no move, or not
//                 let to end without having passed the target (0 % would say it arrived cleanly)
//   settling_s    into the band (2 % of the move) for good, from the start; NaN: still outside at
//                 the end, or not let to end
//   ess_mm        mean |target - position| over the last ess_window_s (the in-position dwell);
//                 NaN: not let to end (a move cut on its way has no steady state)
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace epa::core {

// How a move ended. Numeric values are part of the Modbus interface (move_end): append only.
enum class MoveEnd : std::uint8_t {
  kInPosition = 0,          // within its window for the in-position time
  kCutShort = 1,            // a new target (setpoint or start) came first
  kHalted = 2,              // a halt: recorded until its braking ended
  kStopped = 3,             // the mode changed (STOP, MANUAL) or the appliance shut down
  kFault = 4,               // a fault
  kControllerSwitched = 5,  // the running law was changed during the move
  kTimeout = 6,             // not in position move_window_s after its reference reached the target
  kOffTarget = 7,           // stood still outside its window for the standstill time
};
inline constexpr int kMoveEnds = 8;

std::string_view to_string(MoveEnd end);              // "in_position", "cut_short", ...
std::optional<MoveEnd> parse_move_end(std::string_view name);

struct MoveMetricsOptions {
  double Ts = 0.005;            // s
  double ess_window_s = 0.1;    // the steady-state error's window at the end
  double settling_band = 0.02;  // of the move's length
};

struct MoveMetrics {
  double rise_s, settling_s, ess_mm, overshoot_pct;  // NaN: does not apply (see above)
};

MoveMetrics move_metrics(std::span<const double> y_mm, double from_mm, double target_mm, MoveEnd end,
                         const MoveMetricsOptions& options);

}  // namespace epa::core
