#pragma once
// The points that edit a tuning set, and the fields they edit: how the store keeps an accepted
// tuning write in the running set's row.
#include "points/point_id.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

// Sets the field `point` edits to `value` (controller: 0, 1, 2 as the catalog enumerates it).
// Returns false when `point` is not a tuning point (or the controller number is unknown).
bool apply_tuning_point(TuningSet& set, points::PointId point, double value);

}  // namespace epa::store
