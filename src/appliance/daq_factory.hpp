#pragma once
// Chooses the DAQ backend from the configuration: the only place that knows all three, and which
// plant the sim backend runs (the model's Hammerstein plant, or the physics plant).
#include <memory>
#include <string>

#include "config/appliance_config.hpp"
#include "core/hammerstein_model.hpp"
#include "hal/daq.hpp"
#include "plant/plant_simulator.hpp"

namespace epa::appliance {

struct PhysicsPlantOptions {
  double initial_position_mm = 0.0;
  double initial_pressure_bar = 3.0;
  double noise_std_mm = 0.0;
  std::uint64_t seed = 1;
  int sensor_bits = 0;
  double Ts = 0.005;
};

// The physics plant (epa-pneumatic/1 parameters from `params_path`; "": the defaults). Shared by
// the sim backend and `epa plant-server --plant physics`.
core::Result<std::unique_ptr<plant::PlantSimulator>> make_physics_plant(const std::string& params_path, const PhysicsPlantOptions& options);

core::Result<std::unique_ptr<hal::Daq>> make_daq(const config::ApplianceConfig& appliance, const core::HammersteinModel& model);

}  // namespace epa::appliance
