#pragma once
// Unmodelled effects that can be switched on in the plant simulators and fitted by the sim-to-real
// diagnosis (`epa diagnose`): each a small parametric model with 1-3 parameters in physical units,
// named exactly as the gap report (epa-gap-report/1, docs/formats.md) names them.
//
// Where each acts, in signal order (one sample, valve command u in V -> measured position):
//   u -> input_delay -> valve_lag -> dead zone (+ deadzone_shift) -> gain_change
//     -> position_dependent_gain -> flow_saturation -> ARX (B) -> end stops
//     -> sensor noise -> sensor_quantization
// static_friction, and gain_change's steady_ratio, are a force on the piston: they enter the
// ARX as a second input through the model's mechanical path (force_path.hpp), not through B.
// Everything before the ARX part except position_dependent_gain depends on the command history
// alone (friction on the model's own mechanical speed, which the command history gives), so a
// replay can compute it once per run; position_dependent_gain reads the position,
// sensor_quantization the measurement.
#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/dead_zone.hpp"
#include "core/result.hpp"

namespace epa::plant {

enum class EffectKind {
  kGainChange,             // gain_ratio: the drive u_d scaled (supply pressure, valve gain); steady_ratio;
                           // drift_per_s, drift_settles_s: the gain drifting during each run (a sagging supply)
  kDeadzoneShift,          // shift_r_V, shift_l_V: break points moved
  kInputDelay,             // delay_samples: transport delay of the valve command
  kValveLag,               // tau_s, second_tau_s, rate_V_per_s: spool dynamics, one lag or two in series, a speed limit
  kStaticFriction,         // breakaway_V, coulomb_V: stiction and Coulomb friction on the mechanical speed
  kFlowSaturation,         // ceiling_mm_s: choked flow, a velocity ceiling
  kPositionDependentGain,  // slope_per_100mm, chamber_slope_per_100mm, curvature: gain along the stroke
  kSensorQuantization,     // step_mm: a coarse position sensor
};
inline constexpr std::size_t kEffectCount = 8;
inline constexpr std::array<EffectKind, kEffectCount> kAllEffects = {
    EffectKind::kGainChange,     EffectKind::kDeadzoneShift,  EffectKind::kInputDelay,
    EffectKind::kValveLag,       EffectKind::kStaticFriction, EffectKind::kFlowSaturation,
    EffectKind::kPositionDependentGain, EffectKind::kSensorQuantization};

std::string_view to_string(EffectKind kind);
// The gap report's name; the error lists the eight valid names.
core::Result<EffectKind> parse_effect(std::string_view name);
inline std::size_t index(EffectKind kind) { return static_cast<std::size_t>(kind); }

// One parameter of an effect: name with unit (as in the report), bounds for fitting and for
// validation, and the value at which the effect does nothing.
struct ParamSpec {
  std::string_view name;
  double lo, hi;
  double neutral;
  bool integer = false;    // fitted on a grid of integers (delay)
  std::string_view meaning;
  bool optional = false;   // may be left out of a spec: neutral then
  // A shape parameter that matters only once the others are fitted (with them neutral it changes
  // nothing): its grid runs after them, and only when the effect is fitted afresh.
  bool grid_after_the_rest = false;
  bool log_scale = false;  // fitted on a logarithmic scale (a range of decades)
  // A member of its family of its own (a spool limited by its speed, not by a lag): a fit afresh
  // fits it apart, the rest of its effect neutral, and keeps the better member; later fits leave
  // it out while it stays neutral (diag/effect_fit.cpp).
  bool starts_alone = false;
  // A member fitted only after the selection (diag::FitOptions::fit_last), and in later fits once
  // it is away from its neutral value: free in every fit, it lets the nominal re-fit absorb other
  // effects further (a gain drifting to nothing over a run soaked up a 5.5-sample delay).
  bool fitted_last = false;
};
std::span<const ParamSpec> param_specs(EffectKind kind);

inline constexpr std::size_t kMaxEffectParams = 4;
using EffectParams = std::array<double, kMaxEffectParams>;

// Which effects are on, with their parameters. Default: none (the nominal model).
class EffectSet {
 public:
  void set(EffectKind kind, const EffectParams& params) { on_[index(kind)] = true, params_[index(kind)] = params; }
  void set(EffectKind kind, std::initializer_list<double> params);
  void clear(EffectKind kind) { on_[index(kind)] = false; }
  bool on(EffectKind kind) const { return on_[index(kind)]; }
  const EffectParams& params(EffectKind kind) const { return params_[index(kind)]; }
  double param(EffectKind kind, std::size_t i) const { return params_[index(kind)][i]; }
  std::vector<EffectKind> kinds() const;  // switched on, in signal order
  // Every parameter at its neutral value: the effect, though on, does nothing.
  bool at_neutral(EffectKind kind) const;
  bool empty() const { return kinds().empty(); }
  // Parameters within their bounds (the message names the effect and parameter), finite.
  core::Status validate() const;
  // "input_delay(delay_samples=4), valve_lag(tau_s=0.02)" or "none".
  std::string describe() const;

 private:
  std::array<bool, kEffectCount> on_{};
  std::array<EffectParams, kEffectCount> params_{};
};

// Effects from text, as the simulators' options give them: "valve_lag=0.02",
// "static_friction=0.6,0.3" (the parameters in param_specs order; optional ones left out at the
// end are neutral, so "position_dependent_gain=0.2" is the slope alone). Validated; the
// error names the spec and what is wrong.
core::Result<EffectSet> parse_effect_specs(const std::vector<std::string>& specs);

// Where the piston is, for position_dependent_gain: the mean of the last where_samples positions
// (a parameter of the effect, 2 to kMaxWherePositions). Not the last one alone: the printed B
// swings the model's position by tens of mm at the Nyquist frequency with every change of the
// drive, which no piston does, and a gain fed from that swing feeds on itself. How a rig's gain
// sees past that swing is not known, and the fit is sensitive to it (a blind compressibility rig
// that averages 8: 0.75 mm left with 6 positions, 0.38 mm with 8), so the length is fitted.
inline constexpr std::size_t kDefaultWherePositions = 6;
inline constexpr std::size_t kMaxWherePositions = 12;

// Effects on the valve command only (input_delay, valve_lag): what any plant with a step(valve_v)
// can carry. Explicit state, restartable; the command before sample 0 is taken as 0 V (centred).
class ValveEffects {
 public:
  static constexpr std::size_t kMaxDelaySamples = 63;
  struct State {
    std::array<double, kMaxDelaySamples + 1> past{};  // ring of past commands
    std::size_t head = 0;
    double spool_v = 0.0;   // the lag's output
    double second_v = 0.0;  // the second lag's output
  };
  ValveEffects() = default;
  ValveEffects(const EffectSet& effects, double Ts);
  // The command as the valve's spool sees it at this sample, V.
  double apply(double valve_v) noexcept;
  const State& state() const { return state_; }
  void set_state(const State& s) { state_ = s; }

 private:
  std::size_t delay_ = 0;
  double lag_alpha_ = 1.0;     // 1 - exp(-Ts/tau): 1 is no lag
  double second_alpha_ = 1.0;  // the same for the second lag
  double rate_step_v_ = 0.0;   // the spool's largest step per sample, V (0: no limit)
  State state_;
};

// Effects between the valve and the ARX part, on the drive u_d (V after the dead zone):
// dead zone with deadzone_shift, gain_change, position_dependent_gain, flow_saturation; and the
// force on the piston (static_friction, steady_ratio), which the ARX takes through its
// mechanical path (force_path.hpp). `speed_mm_s_per_V` is the nominal model's steady piston speed
// per volt of u_d, which turns the velocity ceiling into a drive limit; `mechanical_pole` is that
// path's pole, with which the friction follows the piston's mechanical speed.
//
// Friction acts on the mechanical speed v (the drive less the friction, through the pole): while
// |v| exceeds the speed one sample of Coulomb friction takes away, the piston slides against
// coulomb; below it, friction holds the drive up to breakaway (stick), and a drive beyond that
// breaks the piston loose. The valve's flow still reaches B whatever friction does: a stuck
// piston's chambers still fill.
class DriveEffects {
 public:
  struct State {
    double mechanical_speed_mm_s = 0.0;  // v: what friction opposes
    double force_V = 0.0;                // the last sample's force on the piston, volts of drive
    double run_time_s = 0.0;             // since the run started, for gain_change's drift
  };
  DriveEffects() = default;
  // Ts: the sample time, by which each drive_before_position() advances the run's time (0: the
  // time stands still at the run's start, for a shape drawn against something else).
  DriveEffects(const EffectSet& effects, const core::DeadZone& nominal, double Ts, double speed_mm_s_per_V,
               double mechanical_pole = 0.0);
  // The drive before the position-dependent factor and the ceiling (history-dependent part); also
  // advances the force (force()).
  double drive_before_position(double spool_v) noexcept;
  // The force on the piston at the sample drive_before_position last computed, volts of drive:
  // minus the friction, plus (steady_ratio - 1) times the drive.
  double force() const { return state_.force_V; }
  // The friction force (volts of drive) at mechanical speed v with drive d: the form's shape.
  double friction_V(double mechanical_speed_mm_s, double drive_V) const noexcept;
  // gain_change's gain (over the nominal) at a time since the run started: its drift's shape.
  double gain_at(double run_time_s) const noexcept;
  // The position-dependent factor and the ceiling (memoryless part).
  double finish(double drive, double position_mm) const noexcept;
  // Whether finish() reads the position (position_dependent_gain is on and not neutral).
  bool reads_position() const { return slope_per_mm_ != 0.0 || chamber_per_mm_ != 0.0 || curvature_ != 0.0; }
  // How many positions finish()'s position_mm should average (kDefaultWherePositions when off).
  std::size_t where_samples() const { return where_samples_; }
  double apply(double spool_v, double position_mm) noexcept { return finish(drive_before_position(spool_v), position_mm); }
  const State& state() const { return state_; }
  void set_state(const State& s) { state_ = s; }

 private:
  core::DeadZone dead_zone_;
  double Ts_ = 0.0;
  bool friction_ = false;
  double breakaway_ = 0, coulomb_ = 0;
  double speed_mm_s_per_V_ = 0.0, pole_ = 0.0;
  double gain_ = 1.0, steady_extra_ = 0.0, max_drive_ = 0.0;  // max_drive_ 0: no ceiling
  double drift_per_s_ = 0.0, drift_settles_s_ = 0.0;          // gain_change's drift (settles 0: linear)
  double retract_ratio_ = 1.0, knee_ = 64.0;                   // flow_saturation's family
  double slope_per_mm_ = 0.0, chamber_per_mm_ = 0.0, curvature_ = 0.0;  // position_dependent_gain
  std::size_t where_samples_ = kDefaultWherePositions;
  State state_;
};

// sensor_quantization: the reading rounded to the sensor's step (identity for step 0).
double quantize_mm(double position_mm, double step_mm) noexcept;

// Steady piston speed per volt of u_d for y = B/A u_d, y in sensor volts: B(1)/A'(1) with
// A = (1 - q) A', in mm/s. A'(1) = -sum i a_i, which also holds approximately for a model whose
// A has its integrating root only near 1.
double steady_speed_mm_s_per_V(std::span<const double> A, std::span<const double> B, double Ts, double mm_per_volt);

}  // namespace epa::plant
