#include "hal/sim_daq.hpp"

#include "plant/plant_adapter.hpp"

namespace epa::hal {

core::Result<SimDaq> SimDaq::make(const core::HammersteinModel& model, const plant::PlantOptions& options) {
  auto p = plant::make_hammerstein_simulator(model, options);
  if (!p) return p.error();
  return SimDaq(std::move(*p));
}

core::Result<SimDaq> SimDaq::make(std::unique_ptr<plant::PlantSimulator> plant) {
  if (plant == nullptr) return core::invalid_argument("sim DAQ: no plant given");
  return SimDaq(std::move(plant));
}

}  // namespace epa::hal
