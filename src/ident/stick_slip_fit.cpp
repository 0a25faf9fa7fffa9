#include "ident/stick_slip_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <nlopt.hpp>

#include "ident/arx_metrics.hpp"

namespace epa::ident {

namespace {

constexpr std::size_t kParams = 9;
constexpr std::size_t kStartSamples = 5;  // readings averaged for a segment's start position
constexpr double kLossCeilingMm2 = 1e10;  // a diverging simulation scores this
constexpr double kStartBreakShare = 0.9;  // the flow starts a little inside where the piston moves
constexpr double kStartFriction[] = {1.0, 0.25, 2.0};  // times the start's friction levels
constexpr double kStartSpring[] = {1.0, 1.6};          // times its spring
constexpr double kStartSpeed[] = {1.0, 0.85};          // times its speeds (a Hammerstein fit tends high)
constexpr unsigned kPolishRounds = 4;     // restarts from the best point
constexpr double kPolishGain = 0.01;      // a restart that gains less than 1 % of the loss ends them

// One continuous parameter on the unit interval: linear or logarithmic between its bounds.
struct Slot {
  double lo, hi;
  bool log_scale;
  double from_unit(double x) const {
    x = std::clamp(x, 0.0, 1.0);
    return log_scale ? lo * std::pow(hi / lo, x) : lo + (hi - lo) * x;
  }
  double to_unit(double v) const {
    v = std::clamp(v, lo, hi);
    return log_scale ? std::log(v / lo) / std::log(hi / lo) : (v - lo) / (hi - lo);
  }
};

// Wide on purpose: a pneumatic axis lies well inside, and the bounds only keep the integration sane
// (omega h <= 1 at 2 sub-steps of 5 ms).
constexpr std::array<Slot, kParams> kSlots{{
    {0.0, 5.0, false},      // break_right_v
    {-5.0, 0.0, false},     // break_left_v
    {1.0, 5000.0, true},    // speed_right_mm_s_per_v
    {1.0, 5000.0, true},    // speed_left_mm_s_per_v
    {5.0, 400.0, true},     // spring_rad_s
    {0.01, 5.0, true},      // damping_ratio
    {0.01, 200.0, true},    // coulomb_mm
    {0.001, 200.0, true},   // static_mm - coulomb_mm
    {0.0005, 0.3, true},    // spool_lag_s
}};

plant::StickSlipParams from_unit(const double* x, int delay) {
  plant::StickSlipParams p;
  p.break_right_v = kSlots[0].from_unit(x[0]);
  p.break_left_v = kSlots[1].from_unit(x[1]);
  p.speed_right_mm_s_per_v = kSlots[2].from_unit(x[2]);
  p.speed_left_mm_s_per_v = kSlots[3].from_unit(x[3]);
  p.spring_rad_s = kSlots[4].from_unit(x[4]);
  p.damping_ratio = kSlots[5].from_unit(x[5]);
  p.coulomb_mm = kSlots[6].from_unit(x[6]);
  p.static_mm = p.coulomb_mm + kSlots[7].from_unit(x[7]);
  p.spool_lag_s = kSlots[8].from_unit(x[8]);
  p.delay_samples = delay;
  return p;
}

std::vector<double> to_unit(const plant::StickSlipParams& p) {
  const double v[kParams] = {p.break_right_v,  p.break_left_v, p.speed_right_mm_s_per_v,
                             p.speed_left_mm_s_per_v, p.spring_rad_s, p.damping_ratio,
                             p.coulomb_mm, std::max(p.static_mm - p.coulomb_mm, kSlots[7].lo), p.spool_lag_s};
  std::vector<double> x(kParams);
  for (std::size_t i = 0; i < kParams; ++i) x[i] = kSlots[i].to_unit(v[i]);
  return x;
}

double start_position_mm(const Segment& s, double mm_per_volt) {
  const std::size_t n = std::min(kStartSamples, s.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < n; ++k) sum += s.y[k];
  return n ? sum / static_cast<double>(n) * mm_per_volt : 0.0;
}

// One segment's free run from rest at its first readings: at_sample(k, simulated position at k, mm)
// for every sample, allocation-free (the fit runs it thousands of times).
template <typename AtSample>
void replay(plant::StickSlipModel& model, const Segment& s, double mm_per_volt, AtSample&& at_sample) {
  model.reset(start_position_mm(s, mm_per_volt));
  double y = model.position_mm();
  for (std::size_t k = 0; k < s.size(); ++k) {
    at_sample(k, y);
    y = model.step(s.u[k]);
  }
}

// Mean squared simulation error (mm^2) over every sample of every segment.
double simulation_loss(const std::vector<Segment>& segments, const plant::StickSlipParams& p,
                       const StickSlipFitOptions& o) {
  auto model = plant::StickSlipModel::make(p, o.Ts, o.substeps);
  if (!model) return kLossCeilingMm2;
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& s : segments) {
    replay(*model, s, o.mm_per_volt, [&](std::size_t k, double y_mm) {
      const double e = s.y[k] * o.mm_per_volt - y_mm;
      sum += e * e;
    });
    n += s.size();
    if (!(sum < kLossCeilingMm2 * static_cast<double>(n))) return kLossCeilingMm2;
  }
  return n ? sum / static_cast<double>(n) : kLossCeilingMm2;
}

struct Context {
  const std::vector<Segment>* segments;
  const StickSlipFitOptions* options;
  int delay;
  std::size_t evaluations = 0;
};

double objective(unsigned, const double* x, double*, void* data) {
  auto* c = static_cast<Context*>(data);
  ++c->evaluations;
  return simulation_loss(*c->segments, from_unit(x, c->delay), *c->options);
}

// BOBYQA from x; returns the loss at the x it leaves.
double minimise(Context& c, std::vector<double>& x, unsigned evaluations) {
  nlopt::opt opt(nlopt::LN_BOBYQA, kParams);
  opt.set_lower_bounds(std::vector<double>(kParams, 0.0));
  opt.set_upper_bounds(std::vector<double>(kParams, 1.0));
  opt.set_xtol_abs(1e-6);
  opt.set_ftol_rel(1e-8);
  opt.set_maxeval(static_cast<int>(evaluations));
  opt.set_initial_step(0.05);
  opt.set_min_objective(objective, &c);
  double value = std::numeric_limits<double>::infinity();
  try {
    opt.optimize(x, value);
  } catch (const std::exception&) {  // a round-off stop still leaves x usable
    value = objective(kParams, x.data(), nullptr, &c);
  }
  return value;
}

}  // namespace

plant::StickSlipParams stick_slip_start(const core::HammersteinModel& model, std::size_t nk) {
  plant::StickSlipParams p;  // spring, damping, friction and lag: the struct's typical values
  const auto& dz = model.dead_zone;
  p.break_right_v = kStartBreakShare * std::clamp(dz.b_r, kSlots[0].lo, kSlots[0].hi);
  p.break_left_v = kStartBreakShare * std::clamp(dz.b_l, kSlots[1].lo, kSlots[1].hi);
  const double right = core::piston_speed_mm_s_per_v(model, dz.m_r), left = core::piston_speed_mm_s_per_v(model, dz.m_l);
  p.speed_right_mm_s_per_v = std::isfinite(right) ? std::clamp(right, kSlots[2].lo, kSlots[2].hi) : 100.0;
  p.speed_left_mm_s_per_v = std::isfinite(left) ? std::clamp(left, kSlots[3].lo, kSlots[3].hi) : 100.0;
  p.delay_samples = static_cast<int>(std::clamp<std::size_t>(nk, 1, 3) - 1);
  return p;
}

core::Status StickSlipFitOptions::validate() const {
  if (!(Ts > 0.0) || !std::isfinite(Ts)) return core::invalid_argument("stick-slip fit: Ts must be > 0");
  if (!(mm_per_volt > 0.0) || !std::isfinite(mm_per_volt)) return core::invalid_argument("stick-slip fit: mm_per_volt must be > 0");
  if (evaluations_per_start < 10) return core::invalid_argument("stick-slip fit: evaluations_per_start must be >= 10");
  if (starts < 1) return core::invalid_argument("stick-slip fit: starts must be >= 1");
  if (substeps < 1 || substeps > 64) return core::invalid_argument("stick-slip fit: substeps must be within 1..64");
  return core::ok();
}

core::Result<StickSlipFit> fit_stick_slip(const std::vector<Segment>& segments, const plant::StickSlipParams& start,
                                          const StickSlipFitOptions& o) {
  if (auto s = o.validate(); !s) return s.error();
  if (segments.empty()) return core::invalid_argument("stick-slip fit: no segment to fit");
  if (auto s = start.validate(); !s) return s.error();

  const int first_delay = std::clamp(start.delay_samples, 0, 2);
  Context c{&segments, &o, first_delay};
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_x;
  // Friction and the spring are where the loss is most rugged (a stick one sample off moves a whole
  // jump, and a low-friction fit is a local minimum that leaves mm of error), so the starts are a
  // grid over them around the given start.
  for (unsigned i = 0; i < o.starts; ++i) {
    plant::StickSlipParams p = start;
    const double f = kStartFriction[i % std::size(kStartFriction)];
    p.coulomb_mm *= f;
    p.static_mm *= f;
    p.spring_rad_s *= kStartSpring[(i / std::size(kStartFriction)) % std::size(kStartSpring)];
    const double speed = kStartSpeed[(i / (std::size(kStartFriction) * std::size(kStartSpring))) % std::size(kStartSpeed)];
    p.speed_right_mm_s_per_v *= speed;
    p.speed_left_mm_s_per_v *= speed;
    std::vector<double> x = to_unit(p);
    const double value = minimise(c, x, o.evaluations_per_start);
    if (value < best) best = value, best_x = x;
  }
  int best_delay = first_delay;
  for (int delay = 0; delay <= 2; ++delay) {
    if (delay == first_delay) continue;
    Context d{&segments, &o, delay};
    std::vector<double> x = best_x;
    const double value = minimise(d, x, o.evaluations_per_start / 2);
    c.evaluations += d.evaluations;
    if (value < best) best = value, best_x = x, best_delay = delay;
  }
  // BOBYQA stops once its trust region is small, often on a ridge of the rugged loss; a fresh
  // start from the best point finds more until a restart no longer gains.
  for (unsigned round = 0; round < kPolishRounds; ++round) {
    Context p{&segments, &o, best_delay};
    std::vector<double> x = best_x;
    const double value = minimise(p, x, o.evaluations_per_start);
    c.evaluations += p.evaluations;
    const bool gained = value < best * (1.0 - kPolishGain);
    if (value < best) best = value, best_x = x;
    if (!gained) break;
  }
  return StickSlipFit{from_unit(best_x.data(), best_delay), best, c.evaluations};
}

std::vector<std::vector<double>> simulate_stick_slip(const std::vector<Segment>& segments,
                                                     const plant::StickSlipParams& params, double Ts,
                                                     double mm_per_volt, int substeps) {
  std::vector<std::vector<double>> out;
  auto model = plant::StickSlipModel::make(params, Ts, substeps);
  for (const auto& s : segments) {
    std::vector<double> y(s.size(), NAN);
    if (model) replay(*model, s, mm_per_volt, [&](std::size_t k, double y_mm) { y[k] = y_mm / mm_per_volt; });
    out.push_back(std::move(y));
  }
  return out;
}

core::Result<StickSlipIdentification> identify_stick_slip(const std::vector<Segment>& estimation,
                                                          const std::vector<Segment>& validation,
                                                          const core::HammersteinModel& start_model, std::size_t nk,
                                                          const StickSlipFitOptions& options) {
  auto fit = fit_stick_slip(estimation, stick_slip_start(start_model, nk), options);
  if (!fit) return fit.error();
  StickSlipIdentification r;
  r.fit = *fit;
  const auto score = [&](const std::vector<Segment>& segments) {
    return nrmse_fit_percent(segments,
                             simulate_stick_slip(segments, fit->params, options.Ts, options.mm_per_volt, options.substeps), 0);
  };
  r.estimation_pct = score(estimation);
  if (!validation.empty()) r.validation_pct = score(validation);
  r.ramp_right_v = plant::ramp_start_v(fit->params, options.Ts, StickSlipIdentification::kRampVPerS, 1.0);
  r.ramp_left_v = plant::ramp_start_v(fit->params, options.Ts, StickSlipIdentification::kRampVPerS, -1.0);
  return r;
}

}  // namespace epa::ident
