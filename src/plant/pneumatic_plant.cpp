#include "plant/pneumatic_plant.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "core/format.hpp"

namespace epa::plant {

namespace {

// Air as an ideal gas; gamma = 1.4 fixes the nozzle exponents 1/g = 5/7 and (g-1)/g = 2/7.
constexpr double kR = 287.05;  // J/(kg K)
const double kC1 = std::sqrt(1.4 / kR * std::pow(2.0 / 2.4, 2.4 / 0.4));  // choked flow constant
const double kC2 = std::sqrt(2.0 * 1.4 / (kR * 0.4));                      // unchoked flow constant
const double kCriticalRatio = std::pow(2.0 / 2.4, 1.4 / 0.4);             // 0.528
// Above this pressure ratio the isentropic law's infinite slope at r = 1 (flow ~ sqrt(dp)) is
// replaced by a laminar-like quadratic: the physics is viscous there anyway, and the ODE becomes
// Lipschitz, so RK4 approaches pressure equalisation without overshooting it.
constexpr double kLaminarRatio = 0.99;
constexpr double kMaxValveV = 10.0;
constexpr double kMaxSensorV = 10.0;  // sensor: 0-10 V over the stroke
constexpr double kBar = 1e5;

// Unchoked psi(r) and its derivative, r in (Cr, 1).
double psi_unchoked(double r) {
  const double t = std::pow(r, 1.0 / 7.0);
  const double t2 = t * t;
  return kC2 * t2 * t2 * t * std::sqrt(1.0 - t2);
}
double dpsi_unchoked(double r) {
  const double t = std::pow(r, 1.0 / 7.0);
  const double t2 = t * t, q = std::sqrt(1.0 - t2);
  const double dpsi_dt = kC2 * (5.0 * t2 * t2 * q - t2 * t2 * t2 / q);
  return dpsi_dt * t / (7.0 * r);
}

std::string num(double v) { return core::format_number(v); }

}  // namespace

core::Result<PneumaticPlant> PneumaticPlant::make(const PneumaticParams& params, const PneumaticOptions& o) {
  if (auto s = params.validate(); !s) return s.error();
  if (!(o.initial_position_mm >= 0.0 && o.initial_position_mm <= params.stroke_mm))
    return core::invalid_argument("pneumatic plant: initial position " + num(o.initial_position_mm) +
                                  " mm lies outside the stroke [0, " + num(params.stroke_mm) + "] mm");
  if (!(o.initial_pressure_bar >= 0.0 && o.initial_pressure_bar <= params.supply_pressure_bar))
    return core::invalid_argument("pneumatic plant: initial pressure " + num(o.initial_pressure_bar) +
                                  " bar (gauge, chamber B) lies outside [0, supply " + num(params.supply_pressure_bar) + "] bar");
  if (!(o.noise_std_mm >= 0.0) || !std::isfinite(o.noise_std_mm))
    return core::invalid_argument("pneumatic plant: sensor noise must be >= 0 mm, got " + num(o.noise_std_mm));
  if (o.sensor_bits < 0 || o.sensor_bits > 24)
    return core::invalid_argument("pneumatic plant: sensor bits " + std::to_string(o.sensor_bits) +
                                  " is outside 0..24 (0: no quantisation)");
  if (o.command_delay_samples < 0 || o.command_delay_samples > kMaxCommandDelay)
    return core::invalid_argument("pneumatic plant: command delay " + std::to_string(o.command_delay_samples) +
                                  " samples is outside 0.." + std::to_string(kMaxCommandDelay));
  if (!(o.Ts >= 1e-4 && o.Ts <= 1.0))
    return core::invalid_argument("pneumatic plant: Ts " + num(o.Ts) + " s is outside 0.0001..1 s");
  if (o.substeps < 1 || o.substeps > 100000)
    return core::invalid_argument("pneumatic plant: substeps " + std::to_string(o.substeps) + " is outside 1..100000");

  PneumaticPlant p;
  p.params_ = params;
  p.options_ = o;
  const double pi = std::numbers::pi;
  p.area_a_m2_ = pi / 4.0 * std::pow(params.bore_mm * 1e-3, 2);
  p.area_rod_m2_ = pi / 4.0 * std::pow(params.rod_mm * 1e-3, 2);
  p.area_b_m2_ = p.area_a_m2_ - p.area_rod_m2_;
  p.stroke_m_ = params.stroke_mm * 1e-3;
  p.dead_a_m3_ = params.dead_volume_a_cm3 * 1e-6;
  p.dead_b_m3_ = params.dead_volume_b_cm3 * 1e-6;
  p.atm_pa_ = params.atmospheric_pressure_bar * kBar;
  p.supply_pa_ = p.atm_pa_ + params.supply_pressure_bar * kBar;
  p.RT_ = kR * params.temperature_k;
  p.sqrt_T_ = std::sqrt(params.temperature_k);
  p.n_ = params.polytropic_index;
  p.mass_kg_ = params.piston_mass_kg;
  p.Fs_ = params.static_friction_n;
  p.Fc_ = params.coulomb_friction_n;
  p.vs_ = params.stribeck_velocity_mps;
  p.b_ = params.viscous_friction_n_per_mps;
  p.sigma0_ = params.lugre_stiffness_n_per_m;
  p.sigma1_ = params.lugre_damping_n_s_per_m;
  p.orifice_eff_m2_ = params.discharge_coefficient * params.orifice_area_mm2 * 1e-6;
  p.leak_a_m2_ = params.leak_a_mm2 * 1e-6;
  p.leak_b_m2_ = params.leak_b_mm2 * 1e-6;
  p.tau_s_ = params.spool_time_constant_s;
  p.overlap_pos_v_ = params.overlap_pos_v;
  p.overlap_neg_v_ = params.overlap_neg_v;
  // psi = alpha d + beta d^2 on d = 1 - r in [0, d_l]: equal value and slope at r = kLaminarRatio.
  const double d_l = 1.0 - kLaminarRatio, f_l = psi_unchoked(kLaminarRatio), g_l = -dpsi_unchoked(kLaminarRatio);
  p.laminar_beta_ = (g_l * d_l - f_l) / (d_l * d_l);
  p.laminar_alpha_ = g_l - 2.0 * p.laminar_beta_ * d_l;
  p.mm_per_volt_ = params.stroke_mm / kMaxSensorV;
  p.noise_std_v_ = o.noise_std_mm / p.mm_per_volt_;
  p.lsb_v_ = o.sensor_bits > 0 ? kMaxSensorV / std::ldexp(1.0, o.sensor_bits) : 0.0;
  p.max_code_ = o.sensor_bits > 0 ? std::ldexp(1.0, o.sensor_bits) - 1.0 : 0.0;
  p.Ts_ = o.Ts;
  p.substeps_ = o.substeps;
  p.command_delay_ = o.command_delay_samples;
  p.h_ = o.Ts / o.substeps;

  // RK4 is stable for h |lambda| up to about 2.8 on the real and imaginary axes; keep h |lambda|
  // <= 2 for the fastest mode of each kind (bounds, worst case over the stroke and pressures).
  const double V_min = std::min(p.dead_a_m3_, p.dead_b_m3_);
  struct Mode {
    const char* what;
    double rate;  // 1/s
  };
  const Mode modes[] = {
      {"[valve] spool_time_constant_s", 1.0 / p.tau_s_},
      {"chamber pressure equalisation ([valve] orifice_area_mm2 against the dead volumes)",
       p.n_ * p.RT_ * p.orifice_eff_m2_ * p.laminar_alpha_ / (p.sqrt_T_ * V_min)},
      {"the air spring ([cylinder] piston_mass_kg against the dead volumes)",
       std::sqrt(p.n_ * p.supply_pa_ * (p.area_a_m2_ * p.area_a_m2_ / p.dead_a_m3_ + p.area_b_m2_ * p.area_b_m2_ / p.dead_b_m3_) /
                 p.mass_kg_)},
      {"[friction] viscous_friction_n_per_mps against [cylinder] piston_mass_kg", p.b_ / p.mass_kg_},
      {"the Stribeck slope ([friction] stribeck_velocity_mps)",
       (p.Fs_ - p.Fc_) * std::sqrt(2.0 / std::numbers::e) / (p.vs_ * p.mass_kg_)},
      {"the LuGre bristles against the mass ([friction] lugre_stiffness_n_per_m)", std::sqrt(p.sigma0_ / p.mass_kg_)},
      {"the LuGre bristles' damping ([friction] lugre_damping_n_s_per_m)", p.sigma1_ / p.mass_kg_},
  };
  for (const Mode& m : modes) {
    if (p.h_ * m.rate <= 2.0) continue;
    const double needed = std::ceil(o.Ts * m.rate / 2.0);
    return core::invalid_argument("pneumatic plant: substeps " + std::to_string(o.substeps) + " (sub-step " +
                                  num(p.h_) + " s) is too coarse for " + m.what + " (time constant " +
                                  num(1.0 / m.rate) + " s); use at least " + num(needed) + " substeps");
  }

  // Zero net force: p_A A_A = p_B A_B + p_atm A_rod, so p_atm <= p_A <= p_B.
  p.state_.pressure_b_pa = p.atm_pa_ + o.initial_pressure_bar * kBar;
  p.state_.pressure_a_pa = (p.state_.pressure_b_pa * p.area_b_m2_ + p.atm_pa_ * p.area_rod_m2_) / p.area_a_m2_;
  p.state_.position_m = o.initial_position_mm * 1e-3;
  p.state_.rng = core::Random(o.seed);
  p.sample_sensor();
  return p;
}

namespace {
// make()'s options for a plant that takes `next` while running: its start values within `next`'s
// ranges (they are not used, the state carries over).
PneumaticOptions options_for(PneumaticOptions o, const PneumaticParams& next) {
  o.initial_position_mm = std::clamp(o.initial_position_mm, 0.0, next.stroke_mm);
  o.initial_pressure_bar = std::clamp(o.initial_pressure_bar, 0.0, next.supply_pressure_bar);
  return o;
}
}  // namespace

core::Status PneumaticPlant::check_params(const PneumaticParams& next) const {
  auto made = make(next, options_for(options_, next));
  if (!made) return made.error();
  return core::ok();
}

core::Status PneumaticPlant::set_params(const PneumaticParams& next) {
  auto made = make(next, options_for(options_, next));
  if (!made) return made.error();
  const State running = state_;
  const PneumaticOptions options = options_;
  *this = std::move(*made);
  options_ = options;
  set_state(running);
  return core::ok();
}

void PneumaticPlant::set_state(const State& s) {
  state_ = s;
  state_.position_m = std::clamp(s.position_m, 0.0, stroke_m_);
}

double PneumaticPlant::pressure_force_n(double pa, double pb) const noexcept {
  return pa * area_a_m2_ - pb * area_b_m2_ - atm_pa_ * area_rod_m2_;  // the rod's outer end sees atmosphere
}

double PneumaticPlant::orifice_mass_flow(double area_m2, double p_up, double p_down) const noexcept {
  if (area_m2 <= 0.0) return 0.0;
  if (p_up < p_down) return -orifice_mass_flow(area_m2, p_down, p_up);
  p_up = std::max(p_up, 1.0);  // guard: never divide by a vanishing pressure
  const double r = std::max(p_down, 0.0) / p_up;
  double psi;
  if (r <= kCriticalRatio) {
    psi = kC1;
  } else if (r < kLaminarRatio) {
    psi = psi_unchoked(r);
  } else {
    const double d = 1.0 - r;
    psi = laminar_alpha_ * d + laminar_beta_ * d * d;
  }
  return area_m2 * p_up / sqrt_T_ * psi;
}

bool PneumaticPlant::is_held(double x, double force) const noexcept {
  if (x <= 0.0) return force <= Fs_;          // at the cap-end stop: only a force out of it frees it
  if (x >= stroke_m_) return force >= -Fs_;  // at the rod-end stop
  return std::abs(force) <= Fs_;
}

PneumaticPlant::Deriv PneumaticPlant::derivative(const State& s, double u, bool held, double direction) const noexcept {
  Deriv d{};
  d.spool = (u - s.spool_v) / tau_s_;
  const double open_pos = std::clamp((s.spool_v - overlap_pos_v_) / (kMaxValveV - overlap_pos_v_), 0.0, 1.0);
  const double open_neg = std::clamp((overlap_neg_v_ - s.spool_v) / (kMaxValveV + overlap_neg_v_), 0.0, 1.0);
  const double a_pos = orifice_eff_m2_ * open_pos, a_neg = orifice_eff_m2_ * open_neg;
  const double pa = s.pressure_a_pa, pb = s.pressure_b_pa;
  const double mdot_a = orifice_mass_flow(a_pos, supply_pa_, pa) - orifice_mass_flow(a_neg, pa, atm_pa_) -
                        orifice_mass_flow(leak_a_m2_, pa, atm_pa_);
  const double mdot_b = orifice_mass_flow(a_neg, supply_pa_, pb) - orifice_mass_flow(a_pos, pb, atm_pa_) -
                        orifice_mass_flow(leak_b_m2_, pb, atm_pa_);
  const double x = std::clamp(s.position_m, 0.0, stroke_m_);
  const double v = held ? 0.0 : s.velocity_mps;
  const double Va = dead_a_m3_ + area_a_m2_ * x, Vb = dead_b_m3_ + area_b_m2_ * (stroke_m_ - x);
  d.pa = n_ / Va * (RT_ * mdot_a - pa * area_a_m2_ * v);
  d.pb = n_ / Vb * (RT_ * mdot_b + pb * area_b_m2_ * v);
  if (held) return d;  // x and v stay put
  d.x = v;
  if (lugre()) {  // bristles: no hard stick, the friction follows their deflection
    d.z = v - sigma0_ * std::abs(v) * s.bristle_m / stribeck_n(v);
    d.v = (pressure_force_n(pa, pb) - (sigma0_ * s.bristle_m + sigma1_ * d.z + b_ * v)) / mass_kg_;
    return d;
  }
  // Friction opposes the motion the sub-step started with (at v = 0, breaking away: the net
  // force). Not the sign of this stage's velocity: stages either side of v = 0 would cancel it
  // in the RK4 sum, and a piston pushed by less than the sliding friction would creep on.
  const double friction = direction * stribeck_n(v) + b_ * v;
  d.v = (pressure_force_n(pa, pb) - friction) / mass_kg_;
  return d;
}

void PneumaticPlant::substep(double u) noexcept {
  State& s = state_;
  const double force = pressure_force_n(s.pressure_a_pa, s.pressure_b_pa);
  // With LuGre bristles only an end stop holds the piston: at rest in mid-stroke they decide.
  const bool at_end = s.position_m <= 0.0 || s.position_m >= stroke_m_;
  const bool held = s.velocity_mps == 0.0 && (!lugre() || at_end) && is_held(s.position_m, force);
  const double v0 = s.velocity_mps;
  // The direction of motion over this sub-step: the velocity's, or at rest the net force's.
  const double direction = v0 != 0.0 ? (v0 > 0.0 ? 1.0 : -1.0) : (force >= 0.0 ? 1.0 : -1.0);

  // Classic RK4 on (spool, pa, pb, x, v); the mode (held, friction direction at v = 0) is frozen
  // over the sub-step and revisited after it.
  auto at = [&](const Deriv& k, double f) {
    State t = s;
    t.spool_v += f * k.spool;
    t.pressure_a_pa += f * k.pa;
    t.pressure_b_pa += f * k.pb;
    t.position_m += f * k.x;
    t.velocity_mps += f * k.v;
    t.bristle_m += f * k.z;
    return t;
  };
  const double h = h_;
  const Deriv k1 = derivative(s, u, held, direction);
  const Deriv k2 = derivative(at(k1, h / 2), u, held, direction);
  const Deriv k3 = derivative(at(k2, h / 2), u, held, direction);
  const Deriv k4 = derivative(at(k3, h), u, held, direction);
  s.spool_v += h / 6 * (k1.spool + 2 * k2.spool + 2 * k3.spool + k4.spool);
  s.pressure_a_pa += h / 6 * (k1.pa + 2 * k2.pa + 2 * k3.pa + k4.pa);
  s.pressure_b_pa += h / 6 * (k1.pb + 2 * k2.pb + 2 * k3.pb + k4.pb);
  if (held) return;
  s.position_m += h / 6 * (k1.x + 2 * k2.x + 2 * k3.x + k4.x);
  s.velocity_mps += h / 6 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v);
  s.bristle_m += h / 6 * (k1.z + 2 * k2.z + 2 * k3.z + k4.z);

  // Events, resolved at the end of the sub-step.
  if (!lugre() && s.velocity_mps * direction <= 0.0) s.velocity_mps = 0.0;  // reversal (or stop): the stick test decides next
  if (s.position_m <= 0.0) {
    s.position_m = 0.0;  // inelastic end stops: the piston never leaves the stroke
    s.velocity_mps = std::max(s.velocity_mps, 0.0);
  } else if (s.position_m >= stroke_m_) {
    s.position_m = stroke_m_;
    s.velocity_mps = std::min(s.velocity_mps, 0.0);
  }
}

void PneumaticPlant::step(double valve_v) noexcept {
  double u = std::isfinite(valve_v) ? std::clamp(valve_v, -kMaxValveV, kMaxValveV) : 0.0;
  if (command_delay_ > 0) {  // the command sent command_delay_ samples ago reaches the spool now
    auto& line = state_.command_line;
    std::swap(u, line[state_.command_head]);
    state_.command_head = (state_.command_head + 1) % static_cast<std::size_t>(command_delay_);
  }
  for (int i = 0; i < substeps_; ++i) substep(u);
  sample_sensor();
}

void PneumaticPlant::sample_sensor() noexcept {
  double v = position_v() + (noise_std_v_ > 0.0 ? noise_std_v_ * state_.rng.normal() : 0.0);
  if (lsb_v_ > 0.0) v = std::clamp(std::round(v / lsb_v_), 0.0, max_code_) * lsb_v_;  // ADC codes
  state_.measured_v = v;
}

}  // namespace epa::plant
