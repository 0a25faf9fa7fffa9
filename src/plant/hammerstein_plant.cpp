#include "plant/hammerstein_plant.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace epa::plant {

core::Status PlantOptions::validate() const {
  if (!(noise_std_mm >= 0.0) || !std::isfinite(noise_std_mm))
    return core::invalid_argument("plant: sensor noise must be >= 0 mm, got " + std::to_string(noise_std_mm));
  if (!(stroke_mm > 0.0) || !std::isfinite(stroke_mm))
    return core::invalid_argument("plant: stroke must be > 0 mm, got " + std::to_string(stroke_mm));
  if (!(initial_position_mm >= 0.0 && initial_position_mm <= stroke_mm))
    return core::invalid_argument("plant: initial position " + std::to_string(initial_position_mm) +
                                  " mm lies outside the stroke [0, " + std::to_string(stroke_mm) + "] mm");
  return core::ok();
}

core::Result<HammersteinPlant> HammersteinPlant::make(const core::HammersteinModel& model, const PlantOptions& o) {
  if (auto s = model.validate(); !s) return s.error();
  if (model.B[0] != 0.0)
    return core::invalid_argument("plant: B[0] must be 0: y(k) cannot depend on the command computed from y(k)");
  if (auto s = o.validate(); !s) return s.error();
  HammersteinPlant p;
  p.na_ = model.A.size() - 1;
  p.nb_ = model.B.size() - 1;
  for (std::size_t i = 0; i <= p.na_; ++i) p.a_[i] = model.A[i];
  for (std::size_t i = 0; i <= p.nb_; ++i) p.b_[i] = model.B[i];
  p.force_path_ = force_path(model);
  p.dead_zone_ = model.dead_zone;
  p.mm_per_volt_ = model.mm_per_volt;
  p.max_v_ = o.stroke_mm / model.mm_per_volt;
  p.noise_std_v_ = o.noise_std_mm / model.mm_per_volt;
  p.state_.rng = core::Random(o.seed);
  p.state_.y_past.fill(o.initial_position_mm / model.mm_per_volt);  // at rest: constant past
  p.sample_sensor();
  return p;
}

void HammersteinPlant::step(double valve_v, double force_v) noexcept {
  const double ud = dead_zone_.apply(std::isfinite(valve_v) ? valve_v : 0.0);
  // y(k+1) = -a1 y(k) - a2 y(k-1) - ... + b1 u_d(k) + b2 u_d(k-1) + ...  (b0 = 0, checked in make)
  //          + c1 F(k) + c2 F(k-1) + ...                                  (force_path.hpp)
  auto& s = state_;
  for (std::size_t i = s.ud_past.size() - 1; i > 0; --i) s.ud_past[i] = s.ud_past[i - 1], s.force_past[i] = s.force_past[i - 1];
  s.ud_past[0] = ud;  // now u_d(k), u_d(k-1), ...
  s.force_past[0] = std::isfinite(force_v) ? force_v : 0.0;
  double y = 0.0;
  for (std::size_t i = 1; i <= na_; ++i) y -= a_[i] * s.y_past[i - 1];
  for (std::size_t i = 1; i <= nb_; ++i) y += b_[i] * s.ud_past[i - 1];
  for (std::size_t i = 1; i <= force_path_.nc; ++i) y += force_path_.c[i] * s.force_past[i - 1];
  // End stops: the piston cannot leave the stroke; the clamped value is what the model remembers,
  // so a piston held at a stop starts moving back as soon as the command reverses.
  y = std::clamp(y, 0.0, max_v_);
  for (std::size_t i = s.y_past.size() - 1; i > 0; --i) s.y_past[i] = s.y_past[i - 1];
  s.y_past[0] = y;
  sample_sensor();
}

void HammersteinPlant::sample_sensor() noexcept {
  state_.measured_v = state_.y_past[0] + (noise_std_v_ > 0.0 ? noise_std_v_ * state_.rng.normal() : 0.0);
}

double HammersteinPlant::mean_position_mm(std::size_t samples) const {
  const std::size_t n = std::clamp<std::size_t>(samples, 1, state_.y_past.size());
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += state_.y_past[i];
  return sum / static_cast<double>(n) * mm_per_volt_;
}

}  // namespace epa::plant
