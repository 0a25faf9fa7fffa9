#pragma once
// The register-map points that edit a tuning set, and the fields they edit. Point names are the
// public names of the Modbus interface (docs/registers.md), so they are stable.
#include <string_view>

#include "store/tuning_set.hpp"

namespace epa::store {

// Sets the field `point` edits to `value` (controller: 0, 1, 2 as the register enumerates it).
// Returns false when `point` is not a tuning point (or the controller number is unknown).
bool apply_tuning_point(TuningSet& set, std::string_view point, double value);

bool is_tuning_point(std::string_view point);

}  // namespace epa::store
