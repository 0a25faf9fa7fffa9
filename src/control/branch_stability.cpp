#include "control/branch_stability.hpp"

#include "core/format.hpp"

namespace epa::control {

std::string unstable_branches(const std::vector<ClosedLoopBranch>& branches) {
  std::string unstable;
  for (const auto& b : branches)
    if (b.jury.verdict == Stability::kUnstable)
      unstable += (unstable.empty() ? "" : ", ") + b.name + " (max |root| " + core::format_number(b.max_root_abs) + ")";
  return unstable;
}

}  // namespace epa::control
