#pragma once
// An axis for the commissioning tests that is not any model the commissioning fits: the physics
// plant (plant/pneumatic_plant.*) with a rig's hidden perturbations, behind a remote I/O path as
// the appliance meets it: the module steps its plant on its own clock, so a command written after a
// reading reaches the valve at the module's next cycle, as in-process, or one cycle later when the
// request misses it (with probability late_probability, in order); the sensor noise (0.05 mm) and
// the misses have their own seed, and the sensor reads 15 bits, as the remote I/O layout's register.
#include <deque>
#include <random>

#include "plant/pneumatic_plant.hpp"
#include "simulated_axis.hpp"

namespace epa::testing {

class LateCommandPlant {
 public:
  LateCommandPlant(const plant::PneumaticParams& rig, std::uint64_t seed, double late_probability)
      : plant_(*plant::PneumaticPlant::make(rig, {.initial_position_mm = 250.0, .noise_std_mm = 0.05, .seed = seed, .sensor_bits = 15})),
        late_probability_(late_probability),
        io_random_(seed * 7919 + 1) {}

  double measured_mm() const { return plant_.measured_mm(); }

  // The command sent at this sample drives the next step, or (late) the one after.
  void step(double command_v) {
    const bool late = std::bernoulli_distribution(late_probability_)(io_random_);
    in_flight_.push_back({now_ + (late ? 1 : 0), command_v});
    while (!in_flight_.empty() && in_flight_.front().arrives <= now_) valve_v_ = in_flight_.front().command_v, in_flight_.pop_front();
    plant_.step(valve_v_);
    ++now_;
  }

 private:
  struct Sent {
    std::uint64_t arrives;
    double command_v;
  };
  plant::PneumaticPlant plant_;
  double late_probability_;
  std::mt19937_64 io_random_;
  std::deque<Sent> in_flight_;
  std::uint64_t now_ = 0;
  double valve_v_ = 0.0;
};

class PhysicsRigAxis final : public SimulatedAxisOn<LateCommandPlant> {
 public:
  PhysicsRigAxis(const plant::PneumaticParams& rig, std::uint64_t seed, double late_probability, commission::RunningTuning running)
      : SimulatedAxisOn(LateCommandPlant(rig, seed, late_probability), std::move(running)) {}
};

}  // namespace epa::testing
