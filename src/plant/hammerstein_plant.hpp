#pragma once
// The paper's plant as a simulator: valve dead zone, then the ARX model A y = B u_d (y in sensor
// volts), with end stops at both ends of the stroke and optional seeded sensor noise.
// Timing: step(u) applies the valve command u(k), held over [k, k+1), and advances to k+1;
// the one-sample delay is the model's own (B[0] = 0), none is added.
#include <array>

#include "core/hammerstein_model.hpp"
#include "core/random.hpp"
#include "core/result.hpp"
#include "plant/force_path.hpp"

namespace epa::plant {

struct PlantOptions {
  double initial_position_mm = 0.0;  // at rest here at k = 0
  double noise_std_mm = 0.0;         // Gaussian sensor noise (measurement only, not the piston)
  std::uint64_t seed = 1;            // for the noise
  double stroke_mm = 500.0;          // end stops at 0 and stroke_mm

  core::Status validate() const;  // noise >= 0, stroke > 0, the start within the stroke; names the value
};

// Positions the plant remembers: the model's order, and the mean position effects read
// (plant/effects.hpp, kMaxWherePositions).
inline constexpr std::size_t kRememberedPositions = 12;
static_assert(kRememberedPositions >= core::kMaxModelOrder);

class HammersteinPlant {
 public:
  // All the plant's memory, so a run can be saved and replayed from any sample.
  struct State {
    std::array<double, kRememberedPositions> y_past{};   // y(k), y(k-1), ... true position, V
    std::array<double, core::kMaxModelOrder> ud_past{};  // u_d(k-1), u_d(k-2), ... after the dead zone
    std::array<double, core::kMaxModelOrder> force_past{};  // F(k-1), F(k-2), ...: a force on the piston, V of drive
    double measured_v = 0.0;                             // y(k) + noise, what the sensor reads
    core::Random rng;
  };

  // Errors: invalid model (see HammersteinModel::validate), negative noise, bad stroke or start.
  static core::Result<HammersteinPlant> make(const core::HammersteinModel& model, const PlantOptions& options);

  double measured_v() const { return state_.measured_v; }        // sensor reading at k, V
  double measured_mm() const { return state_.measured_v * mm_per_volt_; }
  double position_v() const { return state_.y_past[0]; }         // true position at k, V
  double position_mm() const { return state_.y_past[0] * mm_per_volt_; }
  // The mean of the last `samples` positions (at most kRememberedPositions), mm.
  double mean_position_mm(std::size_t samples) const;

  // Applies valve command u(k) (V; non-finite is taken as 0 V, the centred valve) and advances.
  // `force_v`: a force on the piston over the sample, volts of drive, through the model's
  // mechanical path (force_path.hpp; friction, for the effects of plant/effects.hpp).
  void step(double valve_v, double force_v = 0.0) noexcept;

  const State& state() const { return state_; }
  void set_state(const State& state) { state_ = state; }
  // How a force on the piston enters (step's force_v), from the model.
  const ForcePath& mechanical_path() const { return force_path_; }

 private:
  HammersteinPlant() = default;
  std::array<double, core::kMaxModelOrder + 1> a_{}, b_{};
  std::size_t na_ = 0, nb_ = 0;
  ForcePath force_path_;
  core::DeadZone dead_zone_;
  double mm_per_volt_ = 50.0, max_v_ = 10.0, noise_std_v_ = 0.0;
  State state_;

  void sample_sensor() noexcept;
};

}  // namespace epa::plant
