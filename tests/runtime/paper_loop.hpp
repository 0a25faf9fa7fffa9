#pragma once
// What the scan-cycle tests share: the 5 ms period they step the loop by, the safe valve command,
// and the paper's tuning (pole placement with FF-IDZ) that most of them run.
#include <cstdint>

#include "control/paper_controller.hpp"
#include "runtime/tuning.hpp"

namespace epa::runtime::testing {

inline constexpr std::int64_t kPeriodNs = 5'000'000;
inline constexpr double kSafeV = 0.0;

inline Tuning paper_tuning() { return *make_tuning(control::paper_controller_config(control::ControllerKind::kPpFfidz)); }

}  // namespace epa::runtime::testing
