#pragma once
// A test axis whose mechanics are the stick-slip model itself, driven by pp-traj designed on a
// model file: each move comes back as the run the recorder would write (noisy readings, the valve
// command applied, the target). A term of the plant may change between moves, the piston kept
// where it stands. What the model-health tests feed their estimator and monitor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>

#include "../support/pp_traj_on_model.hpp"
#include "control/controller.hpp"
#include "core/model_file.hpp"
#include "core/random.hpp"
#include "core/run.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::testing {

class StickSlipAxis {
 public:
  static constexpr double kTs = 0.005;
  static constexpr double kNoiseMm = 0.05;

  StickSlipAxis(const core::ModelFile& law_model, const core::StickSlipParams& plant, std::uint64_t seed)
      : law_(*control::ControllerParams::make(pp_traj_config_on(law_model))), plant_(*plant::StickSlipModel::make(plant, kTs)),
        noise_(seed), targets_(seed * 31 + 7) {
    plant_.reset(250.0);
    y_mm_ = 250.0;
  }

  // The plant's terms from the next move on; the piston stays where it stands.
  void change(const core::StickSlipParams& p) {
    plant_ = *plant::StickSlipModel::make(p, kTs);
    plant_.reset(y_mm_);
  }

  // The next seeded target: 20-170 mm away, towards the middle of the stroke.
  double next_target_mm() {
    const double size = 20.0 + 150.0 * targets_.uniform();
    return std::clamp(target_mm_ + (target_mm_ > 250.0 ? -size : size), 30.0, 470.0);
  }

  // One move of `seconds` to `target_mm`, as its run file has it (move number, end, law).
  core::Run move_to(double target_mm, double seconds = 2.5) {
    target_mm_ = target_mm;
    control::controller_new_move(state_);
    core::Run run;
    run.Ts = kTs;
    run.set_meta("controller", "pp-traj");
    run.set_meta("move", std::to_string(++moves_));
    run.set_meta("move_end", "in_position");
    for (int k = 0; k < static_cast<int>(seconds / kTs); ++k) {
      const double reading_mm = y_mm_ + kNoiseMm * noise_.normal();
      const auto u = control::controller_step(law_, state_, target_mm / 50.0, reading_mm / 50.0);
      run.t_s.push_back(k * kTs);
      run.r_mm.push_back(target_mm);
      run.y_mm.push_back(reading_mm);
      run.u_V.push_back(u.valve_v);
      y_mm_ = std::clamp(plant_.step(u.valve_v), 0.0, 500.0);
    }
    return run;
  }
  core::Run next_move() { return move_to(next_target_mm()); }

 private:
  control::ControllerParams law_;
  control::ControllerState state_;
  plant::StickSlipModel plant_;
  core::Random noise_, targets_;
  double y_mm_ = 250.0, target_mm_ = 250.0;
  int moves_ = 0;
};

}  // namespace epa::testing
