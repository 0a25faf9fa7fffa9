#include "control/controller_kind.hpp"

#include <string>

namespace epa::control {

std::string_view to_string(ControllerKind kind) {
  switch (kind) {
    case ControllerKind::kPp: return "pp";
    case ControllerKind::kPpNgidz: return "pp-ngidz";
    case ControllerKind::kPpFfidz: return "pp-ffidz";
  }
  return "?";
}

std::string_view display_name(ControllerKind kind) {
  switch (kind) {
    case ControllerKind::kPp: return "PP";
    case ControllerKind::kPpNgidz: return "PP NG-IDZ";
    case ControllerKind::kPpFfidz: return "PP FF-IDZ";
  }
  return "?";
}

core::Result<ControllerKind> parse_controller_kind(std::string_view name) {
  for (ControllerKind k : kAllControllerKinds)
    if (to_string(k) == name) return k;
  return core::invalid_argument("unknown controller '" + std::string(name) + "': expected pp, pp-ngidz or pp-ffidz");
}

}  // namespace epa::control
