#pragma once
// The stick-slip model (plant/stick_slip_model.hpp) as a plant to simulate a loop on: the model's
// piston between two end stops, read by a position sensor with seeded Gaussian noise. What
// `epa simulate --plant stick-slip` runs on, with the [stick_slip] table `epa identify` wrote.
#include <cstdint>

#include "core/random.hpp"
#include "core/result.hpp"
#include "plant/hammerstein_plant.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::plant {

class StickSlipPlant {
 public:
  // Errors: invalid params or options (noise, stroke, a start outside the stroke), Ts <= 0.
  static core::Result<StickSlipPlant> make(const StickSlipParams& params, double Ts, double mm_per_volt,
                                           const PlantOptions& options);

  // Applies u(k) (V; non-finite is the centred valve) and advances to k + 1. Allocates nothing.
  void step(double valve_v) noexcept;
  double measured_v() const noexcept { return measured_v_; }  // sensor reading at k, V
  double position_mm() const noexcept { return model_.position_mm(); }
  const StickSlipModel& model() const noexcept { return model_; }

 private:
  StickSlipPlant(StickSlipModel model, double mm_per_volt, const PlantOptions& options);
  void sample_sensor() noexcept;

  StickSlipModel model_;
  core::Random rng_;
  double mm_per_volt_, noise_std_mm_, stroke_mm_;
  double measured_v_ = 0.0;
};

}  // namespace epa::plant
