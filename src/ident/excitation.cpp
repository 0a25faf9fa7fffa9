#include "ident/excitation.hpp"

#include <algorithm>
#include <cmath>

#include "core/format.hpp"
#include "plant/plant_adapter.hpp"

namespace epa::ident {

using core::format_number;

namespace {

constexpr double kValveRangeV = 10.0;  // the proportional valve accepts +-10 V
constexpr double kStopMarginMm = 1.0;  // "at an end stop" (as ident_data's default)

}  // namespace

core::Status ExcitationOptions::validate() const {
  auto bad = [](const std::string& what) { return core::Status(core::invalid_argument(what)); };
  if (!(Ts > 0.0 && std::isfinite(Ts))) return bad("Ts must be > 0 s, got " + format_number(Ts));
  if (!(duration_s > 0.0 && std::isfinite(duration_s))) return bad("--duration must be > 0 s, got " + format_number(duration_s));
  if (!(amplitude_max_v > 0.0 && amplitude_max_v <= kValveRangeV))
    return bad("--amplitude-max must lie in (0, 10] V (the valve's range), got " + format_number(amplitude_max_v));
  if (!(amplitude_min_v > 0.0 && amplitude_min_v <= amplitude_max_v))
    return bad("--amplitude-min must lie in (0, --amplitude-max], got " + format_number(amplitude_min_v));
  if (levels < 1) return bad("--levels must be >= 1, got " + std::to_string(levels));
  if (!(pulse_min_s > 0.0 && pulse_min_s <= pulse_max_s))
    return bad("pulse length: need 0 < min <= max, got [" + format_number(pulse_min_s) + ", " + format_number(pulse_max_s) + "] s");
  if (!(rest_min_s >= 0.0 && rest_min_s <= rest_max_s))
    return bad("rest length: need 0 <= min <= max, got [" + format_number(rest_min_s) + ", " + format_number(rest_max_s) + "] s");
  if (!(ramp_rate_v_per_s > 0.0)) return bad("--ramp-rate must be > 0 V/s, got " + format_number(ramp_rate_v_per_s));
  if (!(ramp_travel_mm > 0.0)) return bad("--ramp-travel must be > 0 mm, got " + format_number(ramp_travel_mm));
  if (!(ramp_rest_s >= 0.0)) return bad("ramp rest must be >= 0 s, got " + format_number(ramp_rest_s));
  if (!(stroke_mm > 0.0 && guard_mm >= 0.0 && 2.0 * guard_mm < stroke_mm))
    return bad("--guard must lie in [0, stroke/2) mm, got " + format_number(guard_mm) + " for a " + format_number(stroke_mm) +
               " mm stroke");
  return core::ok();
}

core::Result<ExcitationGenerator> ExcitationGenerator::make(const ExcitationOptions& o) {
  if (auto s = o.validate(); !s) return s.error();
  return ExcitationGenerator(o);
}

ExcitationGenerator::ExcitationGenerator(const ExcitationOptions& o)
    : o_(o), rng_(o.seed), total_(samples(o.duration_s)), motion_v_{NAN, NAN} {}

std::size_t ExcitationGenerator::samples(double seconds) const {
  return static_cast<std::size_t>(std::llround(seconds / o_.Ts));
}

std::size_t ExcitationGenerator::random_samples(double lo_s, double hi_s) {
  return std::max<std::size_t>(1, samples(lo_s + (hi_s - lo_s) * rng_.uniform()));
}

void ExcitationGenerator::start_pulse(double y_mm) {
  const double middle = 0.5 * o_.stroke_mm, half_span = 0.5 * o_.stroke_mm - o_.guard_mm;
  // Either way certain to head back once the piston is half way from the middle to a guard line,
  // so a pulse away from the middle starts with room for its travel (and the piston's coast after
  // the guard cuts it) before the end.
  const double offset = (y_mm - middle) / half_span;  // -1 and +1 at the guard lines
  double p_plus = std::clamp(0.5 - offset, 0.0, 1.0);
  if (o_.sweep) {
    if (sweep_direction_ == 0) sweep_direction_ = offset <= 0.0 ? 1 : -1;
    if (offset >= kSweepTurn) sweep_direction_ = -1;
    if (offset <= -kSweepTurn) sweep_direction_ = 1;
    // The centring rule around a point kSweepBias - 0.5 of the way out on the sweep's side.
    if (std::abs(offset) < 0.5) p_plus = std::clamp(0.5 + sweep_direction_ * (kSweepBias - 0.5) - offset, 0.0, 1.0);
  }
  const double sign = rng_.uniform() < p_plus ? 1.0 : -1.0;
  const int level = o_.levels == 1 ? 0 : static_cast<int>(rng_.uniform() * o_.levels);
  const double amplitude =
      o_.levels == 1 ? o_.amplitude_max_v
                     : o_.amplitude_min_v + (o_.amplitude_max_v - o_.amplitude_min_v) * level / (o_.levels - 1);
  u_ = sign * amplitude;
  left_ = random_samples(o_.pulse_min_s, o_.pulse_max_s);
  phase_ = ExcitationPhase::kPulse;
  ++pulses_;
}

double ExcitationGenerator::next(double y_mm) {
  if (k_ >= total_) {
    phase_ = ExcitationPhase::kDone;
    return u_ = 0.0;
  }
  ++k_;
  const double dir = ramp_ == 0 ? 1.0 : -1.0;
  const double step = o_.ramp_rate_v_per_s * o_.Ts;
  switch (phase_) {
    case ExcitationPhase::kRampUp:
      if (!ramp_started_) ramp_start_mm_ = y_mm, ramp_started_ = true;
      // y(k) shows the commands up to u(k-1), the u_ still held.
      // Motion in the ramp's direction only: a piston still creeping from the ramp before is not
      // moved by this one.
      if (std::isnan(motion_v_[ramp_]) && dir * (y_mm - ramp_start_mm_) > kMotionThresholdMm) motion_v_[ramp_] = u_;
      if (std::abs(y_mm - ramp_start_mm_) >= o_.ramp_travel_mm || std::abs(u_) >= o_.amplitude_max_v) {
        phase_ = ExcitationPhase::kRampBack;
        u_ -= dir * step;
      } else {
        u_ = dir * std::min(std::abs(u_) + step, o_.amplitude_max_v);
      }
      break;
    case ExcitationPhase::kRampBack:
      u_ -= dir * step;
      if (dir * u_ <= 0.0) {
        u_ = 0.0;
        phase_ = ExcitationPhase::kRampRest;
        left_ = samples(o_.ramp_rest_s);
      }
      break;
    case ExcitationPhase::kRampRest:
      u_ = 0.0;
      if (left_ > 0) {
        --left_;
      } else if (ramp_ == 0) {
        ramp_ = 1;
        ramp_started_ = false;
        phase_ = ExcitationPhase::kRampUp;
      } else {
        phase_ = ExcitationPhase::kRest;
        left_ = 0;
      }
      break;
    case ExcitationPhase::kPulse: {
      const bool beyond_guard = (u_ > 0.0 && y_mm > o_.stroke_mm - o_.guard_mm) || (u_ < 0.0 && y_mm < o_.guard_mm);
      if (beyond_guard) ++pulses_cut_;
      if (beyond_guard || left_ == 0) {
        u_ = 0.0;
        phase_ = ExcitationPhase::kRest;
        left_ = random_samples(o_.rest_min_s, o_.rest_max_s);
      } else {
        --left_;
      }
      break;
    }
    case ExcitationPhase::kRest:
      u_ = 0.0;
      if (left_ > 0) --left_;
      if (left_ == 0) start_pulse(y_mm);
      break;
    case ExcitationPhase::kDone:
      u_ = 0.0;
      break;
  }
  return u_;
}

core::Result<ExcitationResult> run_excitation(const core::HammersteinModel& model, const ExcitationOptions& options,
                                              double noise_std_mm, const std::string& source) {
  ExcitationOptions checked = options;
  checked.Ts = model.Ts;
  if (auto s = checked.validate(); !s) return s.error();
  // The noise gets its own stream, so changing --noise does not change the valve sequence.
  auto plant = plant::make_hammerstein_simulator(model, {.initial_position_mm = 0.5 * options.stroke_mm,
                                                         .noise_std_mm = noise_std_mm,
                                                         .seed = options.seed ^ 0x6E6F697365ull,
                                                         .stroke_mm = options.stroke_mm});
  if (!plant) return plant.error();
  return run_excitation(**plant, model.mm_per_volt, options, noise_std_mm, source);
}

core::Result<ExcitationResult> run_excitation(plant::PlantSimulator& plant, double mm_per_volt,
                                              const ExcitationOptions& options, double noise_std_mm,
                                              const std::string& source) {
  ExcitationOptions o = options;
  o.Ts = plant.sample_period_s();
  if (!(mm_per_volt > 0.0 && std::isfinite(mm_per_volt)))
    return core::invalid_argument("excitation: the sensor scale must be > 0 mm/V, got " + format_number(mm_per_volt));
  auto gen = ExcitationGenerator::make(o);
  if (!gen) return gen.error();

  ExcitationResult r;
  core::Run& run = r.run;
  run.Ts = o.Ts;
  run.set_meta("controller", "open-loop");
  run.set_meta("source", source);
  run.set_meta("excitation_seed", std::to_string(o.seed));
  run.set_meta("amplitude_max_V", format_number(o.amplitude_max_v));
  run.set_meta("pulse_signs", o.sweep ? "sweep" : "centring");
  run.set_meta("noise_mm", format_number(noise_std_mm));
  const std::size_t n = gen->total_samples();
  run.t_s.reserve(n);
  run.y_mm.reserve(n);
  run.u_V.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double y_mm = plant.measured_v() * mm_per_volt;
    const double u = gen->next(y_mm);
    if (r.ramps_end_s == 0.0 && (gen->phase() == ExcitationPhase::kPulse || gen->phase() == ExcitationPhase::kRest))
      r.ramps_end_s = static_cast<double>(k) * o.Ts;
    run.t_s.push_back(static_cast<double>(k) * o.Ts);
    run.y_mm.push_back(y_mm);
    run.u_V.push_back(u);
    const double true_mm = plant.position_mm();
    if (true_mm <= kStopMarginMm || true_mm >= o.stroke_mm - kStopMarginMm) ++r.samples_at_stops;
    plant.step(u);
  }
  r.ramp_motion_up_v = gen->ramp_motion_up_v();
  r.ramp_motion_down_v = gen->ramp_motion_down_v();
  r.pulses = gen->pulses();
  r.pulses_cut = gen->pulses_cut();
  return r;
}

}  // namespace epa::ident
