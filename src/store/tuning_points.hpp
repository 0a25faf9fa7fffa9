#pragma once
// The points that edit a tuning set, and the values they edit: how the store keeps an accepted
// tuning write in the running set's row. The point -> value map is the write gate's own
// (points/tuning_values.hpp), so both edit the same value in the same unit.
#include "points/point_id.hpp"
#include "points/tuning_values.hpp"
#include "store/tuning_set.hpp"

namespace epa::store {

// The set's values of the tuning points (in the points' units, as the set keeps them), and back.
points::TuningValues tuning_values(const TuningSet& set);
void set_tuning_values(TuningSet& set, const points::TuningValues& values);

// Sets the value `point` edits to `value` (controller: 0, 1, 2 as the catalog enumerates it).
// Returns false when `point` is not a tuning point (or the controller number is unknown).
bool apply_tuning_point(TuningSet& set, points::PointId point, double value);

}  // namespace epa::store
