#include "plant/plant_adapter.hpp"

namespace epa::plant {

core::Result<std::unique_ptr<PlantSimulator>> make_hammerstein_simulator(const core::HammersteinModel& model,
                                                                         const PlantOptions& options) {
  auto p = HammersteinPlant::make(model, options);
  if (!p) return p.error();
  return std::unique_ptr<PlantSimulator>(
      std::make_unique<PlantAdapter<HammersteinPlant>>(std::move(*p), model.Ts, "Hammerstein"));
}

core::Result<std::unique_ptr<PlantSimulator>> make_augmented_simulator(const core::HammersteinModel& model, const EffectSet& effects,
                                                                       const PlantOptions& options) {
  auto p = AugmentedPlant::make(model, effects, options);
  if (!p) return p.error();
  return std::unique_ptr<PlantSimulator>(
      std::make_unique<PlantAdapter<AugmentedPlant>>(std::move(*p), model.Ts, "Hammerstein with effects"));
}

core::Result<std::unique_ptr<PlantSimulator>> make_pneumatic_simulator(const PneumaticParams& params,
                                                                       const PneumaticOptions& options) {
  auto p = PneumaticPlant::make(params, options);
  if (!p) return p.error();
  return std::unique_ptr<PlantSimulator>(std::make_unique<PlantAdapter<PneumaticPlant>>(std::move(*p), options.Ts, "physics"));
}

}  // namespace epa::plant
