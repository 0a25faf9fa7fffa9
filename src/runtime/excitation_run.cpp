#include "runtime/excitation_run.hpp"

#include "runtime/runtime_config.hpp"

namespace epa::runtime {

ident::ExcitationOptions excitation_options(const ExcitationSettings& s, const RuntimeConfig& config) noexcept {
  ident::ExcitationOptions o;  // levels, pulse, rest and ramp shapes: the generator's defaults, as `epa excite`
  o.Ts = config.period_s;
  o.duration_s = s.duration_s;
  o.amplitude_min_v = s.amplitude_min_v;
  o.amplitude_max_v = s.amplitude_max_v;
  o.stroke_mm = config.soft_max_mm - config.soft_min_mm;
  o.guard_mm = s.guard_mm;
  o.sweep = s.sweep;
  o.seed = s.seed;
  return o;
}

bool ExcitationRun::start(const ExcitationSettings& s, const RuntimeConfig& config, std::uint64_t first_sample) noexcept {
  generator_.reset();
  // Valid settings make no error message, so this allocates nothing (the allocation test runs it).
  auto made = ident::ExcitationGenerator::make(excitation_options(s, config));
  if (!made) return false;
  generator_.emplace(std::move(*made));
  settings_ = s;
  soft_min_mm_ = config.soft_min_mm;
  period_s_ = config.period_s;
  first_sample_ = first_sample;
  given_ = 0;
  return true;
}

double ExcitationRun::next(double position_mm) noexcept {
  if (!generator_) return 0.0;
  ++given_;
  return generator_->next(position_mm - soft_min_mm_);
}

double ExcitationRun::left_s() const noexcept {
  if (!generator_) return 0.0;
  const std::size_t total = generator_->total_samples();
  return static_cast<double>(total > given_ ? total - given_ : 0) * period_s_;
}

}  // namespace epa::runtime
