#pragma once
// The `sim` backend: an in-process plant stepped in lock-step with the loop. Each write_valve()
// advances the plant by one sample, so a scan cycle against it is exactly the closed loop of
// sim::simulate_step (read y(k), write u(k), plant moves to y(k+1)).
#include "core/hammerstein_model.hpp"
#include "hal/daq.hpp"
#include "plant/hammerstein_plant.hpp"

namespace epa::hal {

class SimDaq final : public Daq {
 public:
  static core::Result<SimDaq> make(const core::HammersteinModel& model, const plant::PlantOptions& options);

  std::string describe() const override { return "sim (in-process Hammerstein plant)"; }
  core::Status open() override { return core::ok(); }
  SensorReading read_sensor() noexcept override { return {IoStatus::kOk, plant_.measured_v()}; }
  IoStatus write_valve(double valve_v) noexcept override {
    plant_.step(valve_v);
    return IoStatus::kOk;
  }
  void close() noexcept override {}

  const plant::HammersteinPlant& plant() const { return plant_; }

 private:
  explicit SimDaq(plant::HammersteinPlant p) : plant_(std::move(p)) {}
  plant::HammersteinPlant plant_;
};

}  // namespace epa::hal
