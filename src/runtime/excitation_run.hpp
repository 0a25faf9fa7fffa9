#pragma once
// The excitation experiment inside the scan cycle (mode EXCITE). ident::ExcitationGenerator is
// plain numbers, so it is made in place (std::optional) when the mode is entered and its next()
// runs each cycle without allocating; it is fed the measured position in soft-limit coordinates
// (position - soft_min_mm), so its guard lines lie inside the appliance's soft limits.
#include <cstddef>
#include <cstdint>
#include <optional>

#include "ident/excitation.hpp"
#include "runtime/excitation_settings.hpp"

namespace epa::runtime {

// How an experiment ended: written into its run file. Numeric values are not an interface.
enum class ExcitationEnd : std::uint8_t {
  kComplete,  // every command of the signal was applied; the appliance went to STOP by itself
  kStopped,   // a mode command or a shutdown ended it early
  kFault,     // a fault ended it early (the valve went safe in that cycle)
};

// The generator's options for `s` in soft-limit coordinates.
ident::ExcitationOptions excitation_options(const ExcitationSettings& s, const RuntimeConfig& config) noexcept;

class ExcitationRun {
 public:
  // Starts an experiment whose first sample is the recorder's `first_sample`. `s` must be
  // settings excitation_problem() accepts; false (nothing started) if the generator refused them.
  bool start(const ExcitationSettings& s, const RuntimeConfig& config, std::uint64_t first_sample) noexcept;

  bool active() const noexcept { return generator_.has_value(); }
  bool done() const noexcept { return generator_ && generator_->done(); }  // every command given

  // The valve command u(k) for the position y(k) read at this cycle, V.
  double next(double position_mm) noexcept;

  double left_s() const noexcept;  // of the running experiment; 0 when none runs
  std::size_t pulses() const noexcept { return generator_ ? generator_->pulses() : 0; }
  std::size_t pulses_cut() const noexcept { return generator_ ? generator_->pulses_cut() : 0; }  // at a guard line
  const ExcitationSettings& settings() const noexcept { return settings_; }
  std::uint64_t first_sample() const noexcept { return first_sample_; }

  void end() noexcept { generator_.reset(); }

 private:
  std::optional<ident::ExcitationGenerator> generator_;
  ExcitationSettings settings_;
  double soft_min_mm_ = 0.0, period_s_ = 0.0;
  std::uint64_t first_sample_ = 0;
  std::size_t given_ = 0;  // commands given so far
};

}  // namespace epa::runtime
