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

core::Result<std::unique_ptr<PlantSimulator>> make_stick_slip_simulator(const StickSlipParams& params, double Ts,
                                                                        double mm_per_volt, const PlantOptions& options) {
  auto p = StickSlipPlant::make(params, Ts, mm_per_volt, options);
  if (!p) return p.error();
  return std::unique_ptr<PlantSimulator>(std::make_unique<PlantAdapter<StickSlipPlant>>(std::move(*p), Ts, "stick-slip"));
}

}  // namespace epa::plant
