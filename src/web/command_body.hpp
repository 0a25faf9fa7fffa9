#pragma once
// The bodies of the HTTP command endpoints, read into point writes for the write gate
// (points::WriteGate), which alone decides whether they are taken. Only the JSON is checked here:
//   POST /api/setpoint  {"setpoint_mm": 120}
//   POST /api/mode      {"mode": "run"}            (stop, run, manual)
//   POST /api/reset     {}
//   POST /api/points    {"<point>": value, ...}    any writable points as one group, by their
//                       catalog names; mode and controller also by name ("run", "pp-ffidz"), a
//                       record's controller also "running"
//   POST /api/records   {"record": 3, "target_mm": 120, "speed_mm_s": 50, "window_mm": 0.5,
//                        "controller": "pp-traj"}  one record's fields (any of the four), one group:
//                       the same points as record3_target_mm ... through /api/points
#include <string>
#include <vector>

#include "points/write_gate.hpp"

namespace epa::web {

enum class CommandEndpoint { kSetpoint, kMode, kReset, kPoints, kRecord };

struct CommandBody {
  std::string error;  // set: the body is malformed (HTTP 400), naming what was expected
  std::vector<points::PointWrite> writes;
};

CommandBody parse_command_body(CommandEndpoint endpoint, const std::string& body);

}  // namespace epa::web
