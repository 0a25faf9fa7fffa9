#include "hal/sim_daq.hpp"

namespace epa::hal {

core::Result<SimDaq> SimDaq::make(const core::HammersteinModel& model, const plant::PlantOptions& options) {
  auto p = plant::HammersteinPlant::make(model, options);
  if (!p) return p.error();
  return SimDaq(std::move(*p));
}

}  // namespace epa::hal
