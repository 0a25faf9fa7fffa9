#pragma once
// A position record's law by name, as the JSON API, the page and `epa records` show and take it:
// the controller's own name (pp, pp-ngidz, pp-ffidz, pp-traj) or "running" for kKeepController
// (the move runs with whatever law runs then). The register holds the number. The same for its side
// of approach.
#include <string>
#include <string_view>

#include "core/result.hpp"

namespace epa::points {

inline constexpr std::string_view kRunningControllerName = "running";

// The name of a record's controller value; a value no law has (a damaged table) as its number.
std::string record_controller_name(int controller);
// The value of a name: a controller's, or "running" (255).
core::Result<int> parse_record_controller(std::string_view name);

// A record's side of approach by name: "near", "from-below", "from-above" (RecordApproach); a
// value outside them (a damaged table) as its number.
std::string record_approach_name(int approach);
core::Result<int> parse_record_approach(std::string_view name);

}  // namespace epa::points
