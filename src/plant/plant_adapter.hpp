#pragma once
// The plants behind the PlantSimulator interface, and factories that make them so.
#include <memory>
#include <optional>
#include <string_view>
#include <type_traits>
#include <utility>

#include "core/hammerstein_model.hpp"
#include "core/result.hpp"
#include "plant/augmented_plant.hpp"
#include "plant/hammerstein_plant.hpp"
#include "plant/plant_simulator.hpp"
#include "plant/pneumatic_plant.hpp"
#include "plant/stick_slip_plant.hpp"

namespace epa::plant {

// Wraps a plant with the sample-level interface (step, measured_v, position_mm) by value.
template <typename Plant>
class PlantAdapter final : public PlantSimulator {
 public:
  PlantAdapter(Plant plant, double Ts, std::string_view kind) : plant_(std::move(plant)), Ts_(Ts), kind_(kind) {}

  void step(double valve_v) noexcept override { plant_.step(valve_v); }
  double measured_v() const noexcept override { return plant_.measured_v(); }
  double position_mm() const noexcept override { return plant_.position_mm(); }
  double sample_period_s() const noexcept override { return Ts_; }
  std::string_view kind() const noexcept override { return kind_; }
  std::unique_ptr<PlantSimulator> clone() const override { return std::make_unique<PlantAdapter>(*this); }

  std::optional<PneumaticParams> physics_params() const override {
    if constexpr (kPhysics) return plant_.params();
    else return std::nullopt;
  }
  core::Status check_physics_params(const PneumaticParams& next) const override {
    if constexpr (kPhysics) return plant_.check_params(next);
    else return PlantSimulator::check_physics_params(next);
  }
  core::Status set_physics_params(const PneumaticParams& next) override {
    if constexpr (kPhysics) return plant_.set_params(next);
    else return PlantSimulator::check_physics_params(next);
  }

  const Plant& plant() const { return plant_; }

 private:
  static constexpr bool kPhysics = std::is_same_v<Plant, PneumaticPlant>;
  Plant plant_;
  double Ts_;
  std::string_view kind_;  // a string literal
};

// The paper's Hammerstein plant; Ts is the model's. Errors as HammersteinPlant::make.
core::Result<std::unique_ptr<PlantSimulator>> make_hammerstein_simulator(const core::HammersteinModel& model,
                                                                         const PlantOptions& options);
// The Hammerstein plant with effects switched on (plant::AugmentedPlant): data with an effect the
// diagnosis is not told about. Errors as AugmentedPlant::make.
core::Result<std::unique_ptr<PlantSimulator>> make_augmented_simulator(const core::HammersteinModel& model, const EffectSet& effects,
                                                                       const PlantOptions& options);
// The physics plant; Ts is options.Ts. Errors as PneumaticPlant::make.
core::Result<std::unique_ptr<PlantSimulator>> make_pneumatic_simulator(const PneumaticParams& params,
                                                                       const PneumaticOptions& options);

// The stick-slip model of an axis (epa identify's [stick_slip]) with a sensor. Errors as StickSlipPlant::make.
core::Result<std::unique_ptr<PlantSimulator>> make_stick_slip_simulator(const StickSlipParams& params, double Ts,
                                                                        double mm_per_volt, const PlantOptions& options);

}  // namespace epa::plant
