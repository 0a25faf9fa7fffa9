#pragma once
// The four controllers, named the same everywhere (docs/formats.md): command line, configuration,
// register enumeration (0, 1, 2, 3), run-file metadata and reports.
#include <array>
#include <string_view>

#include "core/result.hpp"

namespace epa::control {

enum class ControllerKind : int {
  kPp = 0,       // pole placement alone
  kPpNgidz = 1,  // with the conventional inverse dead zone as a nonlinear gain
  kPpFfidz = 2,  // with the paper's feed-forward inverse dead zone
  kPpTraj = 3,   // this project's law: the paper's feedback around a model-based trajectory (trajectory_law.hpp)
};

inline constexpr std::array<ControllerKind, 4> kAllControllerKinds = {ControllerKind::kPp, ControllerKind::kPpNgidz,
                                                                      ControllerKind::kPpFfidz, ControllerKind::kPpTraj};

std::string_view to_string(ControllerKind kind);
std::string_view display_name(ControllerKind kind);  // "PP", "PP NG-IDZ", "PP FF-IDZ" as Table 1 heads them, "PP-TRAJ"
core::Result<ControllerKind> parse_controller_kind(std::string_view name);

}  // namespace epa::control
