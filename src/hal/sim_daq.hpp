#pragma once
// The `sim` backend: an in-process plant stepped in lock-step with the loop. Each write_valve()
// advances the plant by one sample, so a scan cycle against it is exactly the closed loop of
// sim::simulate_step (read y(k), write u(k), plant moves to y(k+1)). The plant is any
// plant::PlantSimulator: the paper's Hammerstein model or the physics model.
#include <memory>
#include <string>

#include "core/hammerstein_model.hpp"
#include "hal/daq.hpp"
#include "plant/hammerstein_plant.hpp"
#include "plant/plant_simulator.hpp"

namespace epa::hal {

class SimDaq final : public Daq {
 public:
  // The paper's Hammerstein plant (errors as HammersteinPlant::make).
  static core::Result<SimDaq> make(const core::HammersteinModel& model, const plant::PlantOptions& options);
  // Any plant, e.g. plant::make_pneumatic_simulator(...). Error: a null plant.
  static core::Result<SimDaq> make(std::unique_ptr<plant::PlantSimulator> plant);

  // Copies carry a copy of the plant in its current state (as when the plant was held by value).
  SimDaq(const SimDaq& other) : plant_(other.plant_->clone()) {}
  SimDaq& operator=(const SimDaq& other) {
    if (this != &other) plant_ = other.plant_->clone();
    return *this;
  }
  SimDaq(SimDaq&&) noexcept = default;
  SimDaq& operator=(SimDaq&&) noexcept = default;
  ~SimDaq() override = default;

  std::string describe() const override { return "sim (in-process " + std::string(plant_->kind()) + " plant)"; }
  core::Status open() override { return core::ok(); }
  SensorReading read_sensor() noexcept override { return {IoStatus::kOk, plant_->measured_v()}; }
  IoStatus write_valve(double valve_v) noexcept override {
    plant_->step(valve_v);
    return IoStatus::kOk;
  }
  void close() noexcept override {}

  const plant::PlantSimulator& plant() const { return *plant_; }

 private:
  explicit SimDaq(std::unique_ptr<plant::PlantSimulator> p) : plant_(std::move(p)) {}
  std::unique_ptr<plant::PlantSimulator> plant_;  // never null
};

}  // namespace epa::hal
