#include "plant/stick_slip_plant.hpp"

#include <algorithm>
#include <cmath>

namespace epa::plant {

core::Result<StickSlipPlant> StickSlipPlant::make(const StickSlipParams& params, double Ts, double mm_per_volt,
                                                  const PlantOptions& o) {
  auto model = StickSlipModel::make(params, Ts);
  if (!model) return model.error();
  if (!(mm_per_volt > 0.0) || !std::isfinite(mm_per_volt))
    return core::invalid_argument("stick-slip plant: mm_per_volt must be > 0");
  if (auto s = o.validate(); !s) return s.error();
  return StickSlipPlant(std::move(*model), mm_per_volt, o);
}

StickSlipPlant::StickSlipPlant(StickSlipModel model, double mm_per_volt, const PlantOptions& o)
    : model_(std::move(model)), rng_(o.seed), mm_per_volt_(mm_per_volt), noise_std_mm_(o.noise_std_mm), stroke_mm_(o.stroke_mm) {
  model_.reset(o.initial_position_mm);
  sample_sensor();
}

void StickSlipPlant::step(double valve_v) noexcept {
  const double y = model_.step(valve_v);
  // An end stop takes the piston's speed; the chambers keep their wind-up.
  if (y < 0.0 || y > stroke_mm_) model_.stop_at(std::clamp(y, 0.0, stroke_mm_));
  sample_sensor();
}

void StickSlipPlant::sample_sensor() noexcept {
  const double noise = noise_std_mm_ > 0.0 ? noise_std_mm_ * rng_.normal() : 0.0;
  measured_v_ = (model_.position_mm() + noise) / mm_per_volt_;
}

}  // namespace epa::plant
