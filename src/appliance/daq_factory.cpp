#include "appliance/daq_factory.hpp"

#include "hal/comedi_daq.hpp"
#include "hal/modbus_io_daq.hpp"
#include "hal/sim_daq.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"

namespace epa::appliance {

core::Result<std::unique_ptr<plant::PlantSimulator>> make_physics_plant(const std::string& params_path, const PhysicsPlantOptions& o) {
  plant::PneumaticParams params;  // the defaults, sized like the paper's rig
  if (!params_path.empty()) {
    auto p = plant::read_pneumatic_file(params_path);
    if (!p) return p.error();
    params = *p;
  }
  plant::PneumaticOptions options;
  options.initial_position_mm = o.initial_position_mm;
  options.initial_pressure_bar = o.initial_pressure_bar;
  options.noise_std_mm = o.noise_std_mm;
  options.seed = o.seed;
  options.sensor_bits = o.sensor_bits;
  options.Ts = o.Ts;
  return plant::make_pneumatic_simulator(params, options);
}

core::Result<std::unique_ptr<hal::Daq>> make_daq(const config::ApplianceConfig& appliance, const core::HammersteinModel& model) {
  switch (appliance.backend) {
    case config::HalBackend::kSim: {
      if (appliance.sim_plant == "physics") {
        // Stepped once per scan cycle, so its sample period is the loop's.
        auto plant = make_physics_plant(appliance.physics_config,
                                        {.initial_position_mm = appliance.sim.initial_position_mm,
                                         .initial_pressure_bar = appliance.sim_initial_pressure_bar,
                                         .noise_std_mm = appliance.sim.noise_std_mm, .seed = appliance.sim.seed,
                                         .sensor_bits = appliance.sim_sensor_bits, .Ts = appliance.runtime.period_s});
        if (!plant) return core::invalid_argument("[hal.sim] " + plant.error().message);
        auto daq = hal::SimDaq::make(std::move(*plant));
        if (!daq) return core::invalid_argument("[hal.sim] " + daq.error().message);
        return std::unique_ptr<hal::Daq>(std::make_unique<hal::SimDaq>(std::move(*daq)));
      }
      if (!appliance.sim_effects.empty()) {  // the model with effects hidden in it (test data for epa diagnose)
        auto effects = plant::parse_effect_specs(appliance.sim_effects);
        if (!effects) return core::invalid_argument("[hal.sim] effects: " + effects.error().message);
        auto plant = plant::make_augmented_simulator(model, *effects, appliance.sim);
        if (!plant) return core::invalid_argument("[hal.sim] " + plant.error().message);
        auto daq = hal::SimDaq::make(std::move(*plant));
        if (!daq) return core::invalid_argument("[hal.sim] " + daq.error().message);
        return std::unique_ptr<hal::Daq>(std::make_unique<hal::SimDaq>(std::move(*daq)));
      }
      auto daq = hal::SimDaq::make(model, appliance.sim);
      if (!daq) return core::invalid_argument("[hal.sim] " + daq.error().message);
      return std::unique_ptr<hal::Daq>(std::make_unique<hal::SimDaq>(std::move(*daq)));
    }
    case config::HalBackend::kModbusIo: return std::unique_ptr<hal::Daq>(std::make_unique<hal::ModbusIoDaq>(appliance.modbus_io));
    case config::HalBackend::kComedi: return std::unique_ptr<hal::Daq>(std::make_unique<hal::ComediDaq>(appliance.comedi));
  }
  return core::invalid_argument("unknown DAQ backend");
}

}  // namespace epa::appliance
