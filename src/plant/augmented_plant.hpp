#pragma once
// The Hammerstein plant with unmodelled effects switched on (plant/effects.hpp): the nominal
// dead zone + ARX model, with the effects acting where effects.hpp says, end stops, seeded
// sensor noise and, last, the sensor's quantisation. Same step/state interface as
// HammersteinPlant; with no effects on it gives the same trajectory as HammersteinPlant.
// Timing as HammersteinPlant: step(u) applies u(k), held over [k, k+1), and advances to k+1.
#include "core/hammerstein_model.hpp"
#include "core/random.hpp"
#include "core/result.hpp"
#include "plant/effects.hpp"
#include "plant/hammerstein_plant.hpp"

namespace epa::plant {

class AugmentedPlant {
 public:
  struct State {
    HammersteinPlant::State arx;  // the ARX part (its dead zone is the identity here)
    ValveEffects::State valve;
    DriveEffects::State drive;
    double measured_v = 0.0;
    core::Random rng;
  };

  // Errors: as HammersteinPlant::make, and effect parameters outside their bounds.
  static core::Result<AugmentedPlant> make(const core::HammersteinModel& model, const EffectSet& effects,
                                           const PlantOptions& options);

  double measured_v() const { return measured_v_; }
  double measured_mm() const { return measured_v_ * mm_per_volt_; }
  double position_v() const { return arx_.position_v(); }
  double position_mm() const { return arx_.position_mm(); }

  // Applies valve command u(k) (V; non-finite is taken as 0 V) and advances to k+1.
  void step(double valve_v) noexcept;

  State state() const;
  void set_state(const State& state);

 private:
  AugmentedPlant(HammersteinPlant arx) : arx_(std::move(arx)) {}
  HammersteinPlant arx_;
  ValveEffects valve_;
  DriveEffects drive_;
  double mm_per_volt_ = 50.0, noise_std_v_ = 0.0, step_mm_ = 0.0;
  double measured_v_ = 0.0;
  core::Random rng_;

  void sample_sensor() noexcept;
};

// The valve-side and sensor-side effects (input_delay, valve_lag, sensor_quantization) around
// any plant with step(valve_v), measured_mm() and position_mm(): how the physics plant carries
// them. Effects that act on the drive after the dead zone need the Hammerstein structure
// (AugmentedPlant) and are ignored here.
template <typename Plant>
class WithValveAndSensorEffects {
 public:
  WithValveAndSensorEffects(Plant plant, const EffectSet& effects, double Ts)
      : plant_(std::move(plant)), valve_(effects, Ts),
        step_mm_(effects.on(EffectKind::kSensorQuantization) ? effects.param(EffectKind::kSensorQuantization, 0) : 0.0) {}
  void step(double valve_v) noexcept { plant_.step(valve_.apply(valve_v)); }
  double measured_mm() const { return quantize_mm(plant_.measured_mm(), step_mm_); }
  double position_mm() const { return plant_.position_mm(); }
  Plant& inner() { return plant_; }

 private:
  Plant plant_;
  ValveEffects valve_;
  double step_mm_;
};

}  // namespace epa::plant
