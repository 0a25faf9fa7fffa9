#include "sim/random_moves.hpp"

#include <algorithm>

#include "plant/plant_simulator.hpp"

namespace epa::sim {

RandomMoves::RandomMoves(plant::PlantSimulator& plant, const control::ControllerParams& law, const RandomMovesOptions& options)
    : plant_(plant), law_(law), options_(options), rng_(options.seed * 7919 + 13), target_mm_(options.start_mm) {
  control::controller_start(law_, state_, plant_.measured_v(), 0.0);
}

RecordedMove RandomMoves::next() {
  const double size_mm = rng_.uniform() < 0.4 ? 10.0 + 30.0 * rng_.uniform() : 40.0 + 160.0 * rng_.uniform();
  const double direction = target_mm_ > 400.0 ? -1.0 : target_mm_ < 100.0 ? 1.0 : (rng_.uniform() < 0.5 ? -1.0 : 1.0);
  target_mm_ = std::clamp(target_mm_ + direction * size_mm, 20.0, 480.0);
  control::controller_new_move(state_);
  const double Ts = plant_.sample_period_s();
  RecordedMove move;
  move.run.Ts = Ts;
  for (int k = 0; k < static_cast<int>(options_.move_s / Ts); ++k) {
    const double y_v = plant_.measured_v();
    const auto out = control::controller_step(law_, state_, target_mm_ / options_.mm_per_volt, y_v);
    move.hunted = move.hunted || out.hunting || out.sliding_fallback_started;
    move.run.t_s.push_back(k * Ts);
    move.run.r_mm.push_back(target_mm_);
    move.run.y_mm.push_back(y_v * options_.mm_per_volt);
    move.run.u_V.push_back(out.valve_v);
    move.run.uc_V.push_back(out.controller_v);
    plant_.step(out.valve_v);
  }
  return move;
}

}  // namespace epa::sim
