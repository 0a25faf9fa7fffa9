#pragma once
// A physics model of the rig: a double-acting cylinder driven by a 5/3 closed-centre proportional
// valve, after Richer & Hurmuzlu (2000), "A high performance pneumatic force actuator system",
// ASME J. Dyn. Syst. Meas. Control 122(3). Equations (all SI; x = piston position from the cap
// end, chamber A on the cap side, B on the rod side; pressures absolute):
//
//   spool      ds/dt = (u - s) / tau                       s, u in command volts, |u| <= 10
//   openings   a+ = Cd A0 clamp((s - o+)/(10 - o+), 0, 1)  P->A and B->T   (o+ = overlap_pos_v)
//              a- = Cd A0 clamp((o- - s)/(10 + o-), 0, 1)  P->B and A->T   (o- = overlap_neg_v)
//   orifice    m' = a p_up / sqrt(T) psi(p_down / p_up)    (isentropic nozzle)
//              psi = C1                                      r <= Cr = 0.528 (choked)
//              psi = C2 r^(1/g) sqrt(1 - r^((g-1)/g))        Cr < r < 0.99
//              psi = quadratic in (1 - r) to 0 at r = 1      r >= 0.99 (laminar; C1-continuous)
//   chambers   V_A = V0A + A_A x,  V_B = V0B + A_B (L - x)
//              dp/dt = n / V (R T m' - p dV/dt)              n = polytropic_index (1.4 adiabatic)
//   piston     m dv/dt = p_A A_A - p_B A_B - p_atm A_rod - F_f(v)
//              F_f = sgn(v) [Fc + (Fs - Fc) exp(-(v/vs)^2)] + b v
//
// Discontinuities are handled between RK4 sub-steps, not inside them (Karnopp-like stick model):
// - a piston at rest (v = 0) stays at rest while |net pressure force| <= Fs, and at an end stop
//   while the force pushes into the stop or is below Fs; its pressures still evolve;
// - a velocity reversal within a sub-step ends at v = 0 (then the stick test decides);
// - reaching an end stop is inelastic: x is clamped to [0, L] and v set to 0, so the piston never
//   leaves the stroke.
// These events are located to the sub-step (Ts / substeps), which makes stick-slip runs first
// order in the sub-step; smooth stretches keep RK4's fourth order.
//
// Timing, like HammersteinPlant: step(u) holds u(k) over [k Ts, (k+1) Ts) and advances to k+1;
// measured_v() is the sensor at k (0-10 V over the stroke, seeded noise, then ADC quantisation).
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "core/random.hpp"
#include "core/result.hpp"
#include "plant/pneumatic_params.hpp"

namespace epa::plant {

struct PneumaticOptions {
  double initial_position_mm = 0.0;   // at rest here at k = 0
  // Chamber B's gauge pressure at k = 0; chamber A is set so that the net pressure force is zero,
  // as in a cylinder whose closed-centre valve has been centred for a while. 0: vented cylinder.
  double initial_pressure_bar = 3.0;
  double noise_std_mm = 0.0;          // Gaussian sensor noise (measurement only)
  std::uint64_t seed = 1;             // for the noise
  int sensor_bits = 0;                // ADC resolution over the sensor's 0-10 V; 0: no quantisation
  int command_delay_samples = 0;      // transport delay before the spool (a long line), 0..kMaxCommandDelay
  double Ts = 0.005;                  // sample period, s
  int substeps = 50;                  // RK4 steps per sample
};

class PneumaticPlant {
 public:
  static constexpr int kMaxCommandDelay = 32;
  // All the plant's memory, so a run can be saved and replayed from any sample.
  struct State {
    double spool_v = 0.0;        // spool position in command volts
    double pressure_a_pa = 0.0;  // absolute
    double pressure_b_pa = 0.0;
    double position_m = 0.0;     // 0 .. stroke
    double velocity_mps = 0.0;
    double bristle_m = 0.0;      // LuGre's mean bristle deflection (0 with the stick test)
    double measured_v = 0.0;     // sensor reading at k
    core::Random rng;
    std::array<double, kMaxCommandDelay> command_line{};  // commands in transit (command_delay_samples)
    std::size_t command_head = 0;
  };

  // Errors name the parameter or option: invalid params (PneumaticParams::validate), an initial
  // position outside the stroke, negative noise, bits outside 0..24, a delay outside 0..32, a bad Ts, or a sub-step too
  // long for the stiffest dynamics (with the substeps it needs).
  static core::Result<PneumaticPlant> make(const PneumaticParams& params, const PneumaticOptions& options);

  // Applies valve command u(k) (V, clamped to +-10; non-finite is 0 V, the centred valve) and
  // advances by Ts. Allocates nothing.
  void step(double valve_v) noexcept;

  double measured_v() const { return state_.measured_v; }  // sensor reading at k, V
  double measured_mm() const { return state_.measured_v * mm_per_volt_; }
  double position_mm() const { return state_.position_m * 1e3; }  // true position at k
  double position_v() const { return position_mm() / mm_per_volt_; }
  double velocity_mps() const { return state_.velocity_mps; }
  double pressure_a_pa() const { return state_.pressure_a_pa; }  // absolute
  double pressure_b_pa() const { return state_.pressure_b_pa; }
  double spool_v() const { return state_.spool_v; }
  double Ts() const { return Ts_; }
  int substeps() const { return substeps_; }
  const PneumaticParams& params() const { return params_; }
  // A change of parameters while the plant runs (a worn seal, a lower supply): checks `next` as
  // make() would, for this plant's options, without changing anything ...
  core::Status check_params(const PneumaticParams& next) const;
  // ... and takes it from the next step on. The state carries over (the position clamped to a
  // shorter stroke); on an error nothing changes. Allocates nothing when `next` passed the check.
  core::Status set_params(const PneumaticParams& next);

  // Net pressure force on the piston (N, + towards the stroke end), before friction.
  double pressure_force_n(double pressure_a_pa, double pressure_b_pa) const noexcept;
  // Mass flow (kg/s) through an orifice of effective area area_m2 from p_up to p_down (negative
  // when p_down > p_up): the flow law above, exposed for tests and the diagnosis.
  double orifice_mass_flow(double area_m2, double p_up_pa, double p_down_pa) const noexcept;

  const State& state() const { return state_; }
  // Sets the state as given, except that the position is clamped to the stroke.
  void set_state(const State& state);

 private:
  PneumaticPlant() = default;

  struct Deriv {
    double spool, pa, pb, x, v, z;
  };
  Deriv derivative(const State& s, double u, bool held, double direction) const noexcept;
  bool is_held(double x_m, double force_n) const noexcept;
  void substep(double u) noexcept;
  void sample_sensor() noexcept;

  PneumaticParams params_;
  PneumaticOptions options_;
  // Derived constants in SI units, computed once in make().
  double area_a_m2_ = 0, area_b_m2_ = 0, area_rod_m2_ = 0, stroke_m_ = 0, dead_a_m3_ = 0, dead_b_m3_ = 0;
  double supply_pa_ = 0, atm_pa_ = 0, RT_ = 0, sqrt_T_ = 0, n_ = 0, mass_kg_ = 0;
  double Fs_ = 0, Fc_ = 0, vs_ = 0, b_ = 0;
  double sigma0_ = 0, sigma1_ = 0;  // LuGre; sigma0_ == 0: the stick test
  bool lugre() const noexcept { return sigma0_ > 0.0; }
  // Friction at speed v (m/s) on the Stribeck curve, N: Fs at rest falling to Fc.
  double stribeck_n(double v) const noexcept { return Fc_ + (Fs_ - Fc_) * std::exp(-(v / vs_) * (v / vs_)); }
  double leak_a_m2_ = 0, leak_b_m2_ = 0;  // leaks to atmosphere, effective areas
  double orifice_eff_m2_ = 0, tau_s_ = 0, overlap_pos_v_ = 0, overlap_neg_v_ = 0;
  double laminar_alpha_ = 0, laminar_beta_ = 0;  // psi = alpha d + beta d^2, d = 1 - r, near r = 1
  double mm_per_volt_ = 50.0, noise_std_v_ = 0.0, lsb_v_ = 0.0, max_code_ = 0.0;
  double Ts_ = 0.005, h_ = 1e-4;
  int substeps_ = 50;
  int command_delay_ = 0;
  State state_;
};

}  // namespace epa::plant
