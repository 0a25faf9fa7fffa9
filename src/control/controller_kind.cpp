#include "control/controller_kind.hpp"

#include <string>

namespace epa::control {

namespace {
struct KindNames {
  ControllerKind kind;
  std::string_view name, display;
};
constexpr KindNames kNames[] = {{ControllerKind::kPp, "pp", "PP"},
                                {ControllerKind::kPpNgidz, "pp-ngidz", "PP NG-IDZ"},
                                {ControllerKind::kPpFfidz, "pp-ffidz", "PP FF-IDZ"},
                                {ControllerKind::kPpTraj, "pp-traj", "PP-TRAJ"}};

const KindNames& names_of(ControllerKind kind) {
  for (const auto& n : kNames)
    if (n.kind == kind) return n;
  return kNames[0];  // unreachable for a valid enumerator
}
}  // namespace

std::string_view to_string(ControllerKind kind) { return names_of(kind).name; }
std::string_view display_name(ControllerKind kind) { return names_of(kind).display; }

core::Result<ControllerKind> parse_controller_kind(std::string_view name) {
  for (const auto& n : kNames)
    if (n.name == name) return n.kind;
  return core::invalid_argument("unknown controller '" + std::string(name) + "': expected pp, pp-ngidz, pp-ffidz or pp-traj");
}

}  // namespace epa::control
