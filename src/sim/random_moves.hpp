#pragma once
// An axis under a law making moves between seeded random targets, each recorded from its start for
// a fixed time, as the appliance's recorder writes a move: what the model-health monitor is fed in
// its benchmark (bench/health_drift.cpp) and its tests on the physics plant. The plant is the
// caller's, so that it can change the plant's parameters between moves (wear, a supply drop).
//
// Targets: 40 % of the moves 10-40 mm long, the rest 40-200 mm, each way at random but towards
// the middle while the last target lies within 100 mm of an end; every target within [20, 480] mm.
#include <cstdint>

#include "control/controller.hpp"
#include "core/random.hpp"
#include "core/run.hpp"

namespace epa::plant {
class PlantSimulator;
}

namespace epa::sim {

struct RandomMovesOptions {
  double move_s = 2.5;         // each move's recording, s (the piston rests at its end)
  double mm_per_volt = 50.0;   // the sensor's scale
  double start_mm = 250.0;     // the first move starts from here
  std::uint64_t seed = 1;      // of the targets
};

struct RecordedMove {
  core::Run run;        // t_s, r_mm, y_mm (measured), u_V, uc_V
  bool hunted = false;  // the law's hunting watch fired, or its sliding fallback started
};

class RandomMoves {
 public:
  // The law starts at the plant's reading. plant and law must outlive this object.
  RandomMoves(plant::PlantSimulator& plant, const control::ControllerParams& law, const RandomMovesOptions& options);
  RecordedMove next();

 private:
  plant::PlantSimulator& plant_;
  const control::ControllerParams& law_;
  RandomMovesOptions options_;
  control::ControllerState state_;
  core::Random rng_;
  double target_mm_;
};

}  // namespace epa::sim
