#include "points/record_controller.hpp"

#include "control/controller_kind.hpp"
#include "points/position_records.hpp"

namespace epa::points {

std::string record_controller_name(int controller) {
  if (controller == kKeepController) return std::string(kRunningControllerName);
  for (const auto kind : control::kAllControllerKinds)
    if (static_cast<int>(kind) == controller) return std::string(control::to_string(kind));
  return std::to_string(controller);
}

core::Result<int> parse_record_controller(std::string_view name) {
  if (name == kRunningControllerName) return kKeepController;
  auto kind = control::parse_controller_kind(name);
  if (!kind) return core::invalid_argument("unknown controller '" + std::string(name) + "': expected pp, pp-ngidz, pp-ffidz, pp-traj or " +
                                           std::string(kRunningControllerName) + " (the law running when the record starts)");
  return static_cast<int>(*kind);
}

namespace {
constexpr std::string_view kApproachNames[] = {"near", "from-below", "from-above"};  // RecordApproach's order
}

std::string record_approach_name(int approach) {
  if (approach >= 0 && approach < static_cast<int>(std::size(kApproachNames))) return std::string(kApproachNames[approach]);
  return std::to_string(approach);
}

core::Result<int> parse_record_approach(std::string_view name) {
  for (std::size_t i = 0; i < std::size(kApproachNames); ++i)
    if (name == kApproachNames[i]) return static_cast<int>(i);
  return core::invalid_argument("unknown approach '" + std::string(name) +
                                "': expected near (never past the target), from-below or from-above");
}

}  // namespace epa::points
