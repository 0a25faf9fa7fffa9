#include "plant/effects.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "core/first_order_lag.hpp"
#include "core/format.hpp"

namespace epa::plant {

namespace {

constexpr std::array<std::string_view, kEffectCount> kNames = {
    "gain_change", "deadzone_shift", "input_delay", "valve_lag",
    "static_friction", "flow_saturation", "position_dependent_gain", "sensor_quantization"};

// Bounds are what a fit searches and what validate() accepts. Friction and the shift are in volts:
// shift_* of the valve command (the break points), breakaway/coulomb of the drive u_d after the
// dead zone (about valve volts beyond the break point times the slope, 1.1-1.8 here).
// steady_ratio: the printed B's digits fix its sum, and with it the steady speed, to about
// +-20 % (0.007 +- 0.0015), while they fix its swing closely; a rig within those digits moves
// steadily faster or slower than B says without a gain change. Re-fitted with the nominal
// parameters; it would otherwise pass for friction (a steady speed lost) on effect-free rigs.
// drift_per_s: a family of two members, a gain that holds and one that drifts during each run (a
// receiver that cannot keep up sags its supply pressure while the axis moves, and refills between
// runs): from the run's start at drift_per_s, settling exponentially with drift_settles_s toward
// where the compressor catches up (drift x settles: 1 - exp(-t / settles) of it; linear while t is
// short of it), the gain never below kMinGainFactor. Fitted last, after the selection
// (ParamSpec::fitted_last says why).
constexpr ParamSpec kGain[] = {
    {"gain_ratio", 0.3, 3.0, 1.0, false, "drive (piston speed per volt beyond the break point) over the nominal"},
    {"steady_ratio", 0.7, 1.3, 1.0, false, "steady piston speed over what B gives (B's sum is printed to +-20 %)", true},
    {.name = "drift_per_s", .lo = -0.1, .hi = 0.1, .neutral = 0.0,
     .meaning = "relative change of the gain per second at the run's start (a supply that sags or recovers during a run)",
     .optional = true, .fitted_last = true},
    {.name = "drift_settles_s", .lo = 1.0, .hi = 1000.0, .neutral = 1000.0,
     .meaning = "time constant with which the drift settles (a compressor that catches up); 1000: it does not, linear",
     .optional = true, .log_scale = true, .fitted_last = true}};
constexpr ParamSpec kShift[] = {{"shift_r_V", -1.0, 1.0, 0.0, false, "right break point b_r moved by"},
                                {"shift_l_V", -1.0, 1.0, 0.0, false, "left break point b_l moved by"}};
constexpr ParamSpec kDelay[] = {{"delay_samples", 0.0, 40.0, 0.0, true, "transport delay of the valve command, samples of Ts"}};
// A family: first order (tau_s), or second order with two real poles (second_tau_s > 0: a
// spool with its amplifier, critically or over-damped); and a spool limited by its speed
// (rate_V_per_s below its neutral 5000: a solenoid whose force runs out), met through a rounded
// knee (kSpoolRateKnee) on the first lag's step (on the command's own steps when tau_s is 0).
constexpr ParamSpec kLag[] = {{"tau_s", 0.0, 0.2, 0.0, false, "time constant of the spool's lag"},
                              {"second_tau_s", 0.0, 0.2, 0.0, false, "time constant of a second lag in series (0: first order)", true},
                              {.name = "rate_V_per_s", .lo = 5.0, .hi = 5000.0, .neutral = 5000.0,
                               .meaning = "largest speed of the spool (a solenoid's force limit)", .optional = true,
                               .log_scale = true, .starts_alone = true}};
constexpr ParamSpec kFriction[] = {
    {"breakaway_V", 0.0, 2.0, 0.0, false, "drive u_d friction holds while the piston sticks (stiction)"},
    {"coulomb_V", 0.0, 2.0, 0.0, false, "drive u_d friction takes while the piston slides"}};
// A family: a ceiling on the drive's speed, reached softly or sharply (the knee: speed =
// s / (1 + |s / ceiling|^n)^(1/n) of the unsaturated speed s, n the knee's sharpness; n = 64 is a
// hard clip), and lower or higher one way (a rod side that chokes first).
constexpr ParamSpec kSaturation[] = {
    {.name = "ceiling_mm_s", .lo = 20.0, .hi = 5000.0, .neutral = 5000.0, .meaning = "largest piston speed extending (choked flow)",
     .log_scale = true},
    {.name = "retract_over_extend", .lo = 0.5, .hi = 2.0, .neutral = 1.0,
     .meaning = "the ceiling retracting over the ceiling extending", .optional = true, .log_scale = true},
    {.name = "knee_sharpness", .lo = 1.5, .hi = 64.0, .neutral = 64.0,
     .meaning = "how sharply the speed meets its ceiling: 64 a hard clip, 2 a soft knee", .optional = true, .log_scale = true}};
// A family, not one form: a gain that changes along the stroke the same way in both directions
// (slope), one that falls as the driving chamber lengthens (air compressibility: extending, the
// cap-side chamber grows with the position; retracting, the rod side grows as it falls), and one
// that differs between mid-stroke and the ends (curvature, zero mean over the stroke).
constexpr ParamSpec kPosition[] = {
    {"slope_per_100mm", -0.8, 0.8, 0.0, false, "relative gain change per 100 mm from mid-stroke (250 mm), both directions"},
    {"chamber_slope_per_100mm", -0.8, 0.8, 0.0, false,
     "relative gain fall per 100 mm the driving chamber is longer than at mid-stroke", true},
    {"curvature", -0.8, 0.8, 0.0, false, "relative gain at the ends over mid-stroke, (x/250 mm - 1)^2 - 1/3 shaped", true},
    {"where_samples", 2.0, static_cast<double>(kMaxWherePositions), static_cast<double>(kDefaultWherePositions), true,
     "positions averaged for where the piston is (effects.hpp says why)", true, true}};
constexpr ParamSpec kQuantization[] = {{"step_mm", 0.0, 10.0, 0.0, false, "position sensor resolution"}};

constexpr double kMidStrokeMm = 250.0;
constexpr double kMinPositionFactor = 0.05;  // the drive never reverses along the stroke
constexpr double kMinGainFactor = 0.05;      // nor as the gain drifts
// How sharply the spool's speed meets its limit (the flow ceiling's knee, soft_ceiling): 16 rounds
// only the last few per cent, as a solenoid's force runs out. Fitted, it went to its sharpest
// end on every speed-limited rig, so it is not a parameter.
constexpr double kSpoolRateKnee = 16.0;

// The knee both ceilings share (the spool's speed, the piston's): s / (1 + |s / c|^n)^(1/n) of
// the unlimited s, n the knee's sharpness; n >= 64 is a hard clip.
double soft_ceiling(double s, double c, double n) {
  return n >= 64.0 ? std::clamp(s, -c, c) : s / std::pow(1.0 + std::pow(std::abs(s) / c, n), 1.0 / n);
}


}  // namespace

std::string_view to_string(EffectKind kind) { return kNames[index(kind)]; }

core::Result<EffectKind> parse_effect(std::string_view name) {
  for (std::size_t i = 0; i < kEffectCount; ++i)
    if (kNames[i] == name) return kAllEffects[i];
  std::string all;
  for (auto n : kNames) all += (all.empty() ? "" : ", ") + std::string(n);
  return core::invalid_argument("unknown effect '" + std::string(name) + "' (expected one of: " + all + ")");
}

std::span<const ParamSpec> param_specs(EffectKind kind) {
  switch (kind) {
    case EffectKind::kGainChange: return kGain;
    case EffectKind::kDeadzoneShift: return kShift;
    case EffectKind::kInputDelay: return kDelay;
    case EffectKind::kValveLag: return kLag;
    case EffectKind::kStaticFriction: return kFriction;
    case EffectKind::kFlowSaturation: return kSaturation;
    case EffectKind::kPositionDependentGain: return kPosition;
    case EffectKind::kSensorQuantization: return kQuantization;
  }
  return {};
}

void EffectSet::set(EffectKind kind, std::initializer_list<double> params) {
  EffectParams p{};
  const auto specs = param_specs(kind);
  for (std::size_t i = 0; i < specs.size(); ++i) p[i] = i < params.size() ? params.begin()[i] : specs[i].neutral;
  set(kind, p);
}

std::vector<EffectKind> EffectSet::kinds() const {
  std::vector<EffectKind> k;
  for (auto kind : kAllEffects)
    if (on(kind)) k.push_back(kind);
  return k;
}

bool EffectSet::at_neutral(EffectKind kind) const {
  const auto specs = param_specs(kind);
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (params(kind)[i] != specs[i].neutral) return false;
  return true;
}

core::Status EffectSet::validate() const {
  for (auto kind : kinds()) {
    const auto specs = param_specs(kind);
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const double v = params(kind)[i];
      if (!std::isfinite(v) || v < specs[i].lo || v > specs[i].hi)
        return core::invalid_argument("effect " + std::string(to_string(kind)) + ": " + std::string(specs[i].name) + " = " +
                                      core::format_number(v) + " lies outside [" + core::format_number(specs[i].lo) + ", " +
                                      core::format_number(specs[i].hi) + "]");
      if (specs[i].integer && v != std::round(v))
        return core::invalid_argument("effect " + std::string(to_string(kind)) + ": " + std::string(specs[i].name) + " = " +
                                      core::format_number(v) + " is not a whole number");
    }
  }
  return core::ok();
}

std::string EffectSet::describe() const {
  std::string s;
  for (auto kind : kinds()) {
    s += (s.empty() ? "" : ", ") + std::string(to_string(kind)) + "(";
    const auto specs = param_specs(kind);
    for (std::size_t i = 0; i < specs.size(); ++i)
      s += (i ? ", " : "") + std::string(specs[i].name) + "=" + core::format_number(params(kind)[i]);
    s += ")";
  }
  return s.empty() ? "none" : s;
}

ValveEffects::ValveEffects(const EffectSet& e, double Ts) {
  if (e.on(EffectKind::kInputDelay))
    delay_ = std::min<std::size_t>(kMaxDelaySamples, static_cast<std::size_t>(std::llround(std::max(0.0, e.param(EffectKind::kInputDelay, 0)))));
  if (e.on(EffectKind::kValveLag)) {
    lag_alpha_ = core::lag_step_share(e.param(EffectKind::kValveLag, 0), Ts);
    second_alpha_ = core::lag_step_share(e.param(EffectKind::kValveLag, 1), Ts);
    const double rate = e.param(EffectKind::kValveLag, 2);
    if (rate < kLag[2].neutral) rate_step_v_ = rate * Ts;
  }
}

double ValveEffects::apply(double valve_v) noexcept {
  double u = valve_v;
  if (delay_ > 0) {
    auto& s = state_;
    s.past[s.head] = valve_v;
    const std::size_t n = s.past.size();
    u = s.past[(s.head + n - delay_) % n];
    s.head = (s.head + 1) % n;
  }
  const double step = lag_alpha_ * (u - state_.spool_v);
  state_.spool_v += rate_step_v_ > 0.0 ? soft_ceiling(step, rate_step_v_, kSpoolRateKnee) : step;
  const double first = lag_alpha_ >= 1.0 && rate_step_v_ <= 0.0 ? u : state_.spool_v;
  state_.second_v += second_alpha_ * (first - state_.second_v);
  return second_alpha_ >= 1.0 ? first : state_.second_v;
}

DriveEffects::DriveEffects(const EffectSet& e, const core::DeadZone& nominal, double Ts, double speed_mm_s_per_V,
                           double mechanical_pole)
    : dead_zone_(nominal), Ts_(Ts), speed_mm_s_per_V_(speed_mm_s_per_V), pole_(mechanical_pole) {
  if (e.on(EffectKind::kDeadzoneShift)) {
    dead_zone_.b_r += e.param(EffectKind::kDeadzoneShift, 0);
    dead_zone_.b_l += e.param(EffectKind::kDeadzoneShift, 1);
    if (dead_zone_.b_l > dead_zone_.b_r) dead_zone_.b_l = dead_zone_.b_r = 0.5 * (dead_zone_.b_l + dead_zone_.b_r);
  }
  if (e.on(EffectKind::kStaticFriction)) {
    friction_ = true;
    coulomb_ = e.param(EffectKind::kStaticFriction, 1);
    breakaway_ = std::max(e.param(EffectKind::kStaticFriction, 0), coulomb_);  // stiction is never below Coulomb
  }
  if (e.on(EffectKind::kGainChange)) {
    gain_ = e.param(EffectKind::kGainChange, 0);
    steady_extra_ = e.param(EffectKind::kGainChange, 1) - 1.0;
    drift_per_s_ = e.param(EffectKind::kGainChange, 2);
    drift_settles_s_ = e.param(EffectKind::kGainChange, 3);
  }
  if (e.on(EffectKind::kPositionDependentGain)) {
    slope_per_mm_ = e.param(EffectKind::kPositionDependentGain, 0) / 100.0;
    chamber_per_mm_ = e.param(EffectKind::kPositionDependentGain, 1) / 100.0;
    curvature_ = e.param(EffectKind::kPositionDependentGain, 2);
    where_samples_ = static_cast<std::size_t>(
        std::clamp(std::lround(e.param(EffectKind::kPositionDependentGain, 3)), 1L, static_cast<long>(kMaxWherePositions)));
  }
  if (e.on(EffectKind::kFlowSaturation) && speed_mm_s_per_V > 0.0) {
    max_drive_ = e.param(EffectKind::kFlowSaturation, 0) / speed_mm_s_per_V;
    retract_ratio_ = e.param(EffectKind::kFlowSaturation, 1);
    knee_ = e.param(EffectKind::kFlowSaturation, 2);
  }
}

double DriveEffects::friction_V(double v, double d) const noexcept {
  if (!friction_) return 0.0;
  // Sliding: faster than one sample of Coulomb friction can stop (the mechanical path's first
  // sample is (1 - p) of the steady speed).
  const double sliding_mm_s = (1.0 - pole_) * speed_mm_s_per_V_ * coulomb_;
  if (std::abs(v) > sliding_mm_s) return std::copysign(coulomb_, v);
  return std::clamp(d, -breakaway_, breakaway_);
}

double DriveEffects::gain_at(double run_time_s) const noexcept {
  if (drift_per_s_ == 0.0) return gain_;
  const double drifted = drift_settles_s_ > 0.0 ? drift_per_s_ * drift_settles_s_ * -std::expm1(-run_time_s / drift_settles_s_)
                                                : drift_per_s_ * run_time_s;
  return gain_ * std::max(kMinGainFactor, 1.0 + drifted);
}

double DriveEffects::drive_before_position(double spool_v) noexcept {
  const double d = dead_zone_.apply(spool_v) * gain_at(state_.run_time_s);
  state_.run_time_s += Ts_;
  double force = steady_extra_ * d;
  if (friction_) {
    auto& v = state_.mechanical_speed_mm_s;
    const double f = friction_V(v, d);
    force -= f;
    v = pole_ * v + (1.0 - pole_) * speed_mm_s_per_V_ * (d - f);
  }
  state_.force_V = force;
  return d;
}

double DriveEffects::finish(double drive, double position_mm) const noexcept {
  double d = drive;
  if (reads_position()) {
    const double from_mid_mm = position_mm - kMidStrokeMm, xi = from_mid_mm / kMidStrokeMm;
    // Extending (d > 0) the driving chamber is longer the further out; retracting, the nearer in.
    const double chamber_longer_mm = d >= 0.0 ? from_mid_mm : -from_mid_mm;
    d *= std::max(kMinPositionFactor, 1.0 + slope_per_mm_ * from_mid_mm - chamber_per_mm_ * chamber_longer_mm +
                                          curvature_ * (xi * xi - 1.0 / 3.0));
  }
  if (max_drive_ > 0.0) {
    const double ceiling = d >= 0.0 ? max_drive_ : max_drive_ * retract_ratio_;
    d = soft_ceiling(d, ceiling, knee_);
  }
  return d;
}

double quantize_mm(double position_mm, double step_mm) noexcept {
  return step_mm > 0.0 ? step_mm * std::round(position_mm / step_mm) : position_mm;
}

double steady_speed_mm_s_per_V(std::span<const double> A, std::span<const double> B, double Ts, double mm_per_volt) {
  double b1 = 0.0, a_prime_1 = 0.0;
  for (double b : B) b1 += b;
  for (std::size_t i = 1; i < A.size(); ++i) a_prime_1 -= static_cast<double>(i) * A[i];
  if (a_prime_1 == 0.0) return 0.0;
  return std::abs(b1 / a_prime_1) * mm_per_volt / Ts;
}

core::Result<EffectSet> parse_effect_specs(const std::vector<std::string>& specs) {
  EffectSet set;
  for (const auto& spec : specs) {
    const auto eq = spec.find('=');
    if (eq == std::string::npos) return core::invalid_argument("effect '" + spec + "': write name=value[,value...]");
    auto kind = parse_effect(spec.substr(0, eq));
    if (!kind) return core::invalid_argument("effect '" + spec + "': " + kind.error().message);
    const auto params = param_specs(*kind);
    std::vector<double> values;
    std::string rest = spec.substr(eq + 1);
    for (std::size_t start = 0; start <= rest.size();) {
      const auto comma = rest.find(',', start);
      const std::string item = rest.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      char* end = nullptr;
      const double v = std::strtod(item.c_str(), &end);
      if (item.empty() || end != item.c_str() + item.size())
        return core::invalid_argument("effect '" + spec + "': '" + item + "' is not a number");
      values.push_back(v);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    while (values.size() < params.size() && params[values.size()].optional) values.push_back(params[values.size()].neutral);
    if (values.size() != params.size()) {
      std::string names;
      for (const auto& p : params) names += (names.empty() ? "" : ",") + std::string(p.name);
      return core::invalid_argument("effect '" + spec + "': " + std::string(to_string(*kind)) + " takes " +
                                    std::to_string(params.size()) + " value(s): " + names);
    }
    EffectParams p{};
    std::copy(values.begin(), values.end(), p.begin());
    set.set(*kind, p);
  }
  if (auto s = set.validate(); !s) return s.error();
  return set;
}

}  // namespace epa::plant
