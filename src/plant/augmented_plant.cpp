#include "plant/augmented_plant.hpp"

#include <cmath>

static_assert(epa::plant::kMaxWherePositions <= epa::plant::kRememberedPositions,
              "the plant must remember every position position_dependent_gain may average");

namespace epa::plant {

core::Result<AugmentedPlant> AugmentedPlant::make(const core::HammersteinModel& model, const EffectSet& effects,
                                                  const PlantOptions& options) {
  if (auto s = effects.validate(); !s) return s.error();
  // The inner plant runs the ARX part on the drive: identity dead zone, no noise (added here,
  // before the quantisation, as a sensor does).
  core::HammersteinModel arx_model = model;
  arx_model.dead_zone = {.m_r = 1.0, .m_l = 1.0, .b_r = 0.0, .b_l = 0.0};
  PlantOptions inner = options;
  inner.noise_std_mm = 0.0;
  auto arx = HammersteinPlant::make(arx_model, inner);
  if (!arx) return arx.error();
  if (auto s = model.dead_zone.validate(); !s) return s.error();
  if (!(options.noise_std_mm >= 0.0)) return core::invalid_argument("plant: sensor noise must be >= 0 mm");
  AugmentedPlant p(std::move(*arx));
  p.valve_ = ValveEffects(effects, model.Ts);
  const auto& path = p.arx_.mechanical_path();
  p.drive_ = DriveEffects(effects, model.dead_zone, model.Ts, path.speed_mm_s_per_V, path.pole);
  p.mm_per_volt_ = model.mm_per_volt;
  p.noise_std_v_ = options.noise_std_mm / model.mm_per_volt;
  p.step_mm_ = effects.on(EffectKind::kSensorQuantization) ? effects.param(EffectKind::kSensorQuantization, 0) : 0.0;
  p.rng_ = core::Random(options.seed);
  p.sample_sensor();
  return p;
}

void AugmentedPlant::step(double valve_v) noexcept {
  const double spool_v = valve_.apply(std::isfinite(valve_v) ? valve_v : 0.0);
  const double drive = drive_.apply(spool_v, arx_.mean_position_mm(drive_.where_samples()));
  arx_.step(drive, drive_.force());
  sample_sensor();
}

void AugmentedPlant::sample_sensor() noexcept {
  const double noisy_mm = arx_.position_mm() + (noise_std_v_ > 0.0 ? noise_std_v_ * rng_.normal() * mm_per_volt_ : 0.0);
  measured_v_ = quantize_mm(noisy_mm, step_mm_) / mm_per_volt_;
}

AugmentedPlant::State AugmentedPlant::state() const {
  return {.arx = arx_.state(), .valve = valve_.state(), .drive = drive_.state(), .measured_v = measured_v_, .rng = rng_};
}

void AugmentedPlant::set_state(const State& s) {
  arx_.set_state(s.arx);
  valve_.set_state(s.valve);
  drive_.set_state(s.drive);
  measured_v_ = s.measured_v;
  rng_ = s.rng;
}

}  // namespace epa::plant
