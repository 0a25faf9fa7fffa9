#pragma once
// A simulated axis for the commissioning tests: a Hammerstein plant stepped in the calling thread
// (no real time), tuning sets kept in memory, every switch recorded for the assertions.
#include <map>
#include <vector>

#include "commission/axis.hpp"
#include "commission/commission_sequence.hpp"
#include "control/controller.hpp"
#include "core/paper_reference.hpp"
#include "ident/excitation.hpp"
#include "plant/hammerstein_plant.hpp"

namespace epa::testing {

class SimulatedAxis final : public commission::Axis {
 public:
  // `plant_model` is the axis; `running` the set (with its model) it runs at first, id 1.
  SimulatedAxis(const core::HammersteinModel& plant_model, commission::RunningTuning running)
      : plant_(*plant::HammersteinPlant::make(plant_model, {.initial_position_mm = 250.0, .noise_std_mm = 0.05})) {
    running.set.id = 1;
    running.model.id = 1;
    sets_[1] = running;
  }

  double position_mm() override { return plant_.measured_mm(); }
  double setpoint_min_mm() const override { return 20.0; }
  double setpoint_max_mm() const override { return 480.0; }

  core::Result<core::Run> excite(const commission::ExcitationRequest& r, const std::atomic<bool>& abort) override {
    ++excitations;
    auto gen = ident::ExcitationGenerator::make({.duration_s = r.duration_s, .amplitude_max_v = r.amplitude_max_v, .seed = r.seed});
    if (!gen) return gen.error();
    core::Run run;
    run.Ts = 0.005;
    run.set_meta("controller", "open-loop");
    run.set_meta("excitation_seed", std::to_string(r.seed));
    for (std::size_t k = 0; !gen->done() && !abort; ++k) {
      const double y = plant_.measured_mm(), u = gen->next(y);
      run.t_s.push_back(static_cast<double>(k) * run.Ts), run.r_mm.push_back(0.0), run.y_mm.push_back(y);
      run.u_V.push_back(u), run.uc_V.push_back(u);
      max_abs_valve_v = std::max(max_abs_valve_v, std::abs(u));
      plant_.step(u);
    }
    return run;
  }

  core::Result<commission::RunningTuning> running() override { return sets_.at(loop_set); }

  core::Result<std::int64_t> save(const store::ModelRecord& model, const store::TuningSet& set) override {
    const std::int64_t id = static_cast<std::int64_t>(sets_.size()) + 1;
    commission::RunningTuning t{set, model};
    t.set.id = id;
    sets_[id] = t;
    return id;
  }

  core::Status use_set(std::int64_t id, bool persist, const std::string& reason) override {
    if (!sets_.contains(id)) return core::invalid_argument("no set " + std::to_string(id));
    loop_set = id;
    if (persist) stored_active = id;
    switches.push_back({id, persist, reason});
    return core::ok();
  }

  core::Result<core::Run> move(double target_mm, double hold_s, const std::atomic<bool>& abort) override {
    const auto& t = sets_.at(loop_set);
    auto params = control::ControllerParams::make(store::controller_config(t.set, t.model.model, 0.0));
    if (!params) return params.error();
    control::ControllerState state;
    core::Run run;
    run.Ts = 0.005;
    const double mpv = t.model.model.mm_per_volt;
    for (std::size_t k = 0; k < static_cast<std::size_t>(hold_s / run.Ts) && !abort; ++k) {
      const double y = plant_.measured_mm();
      const auto out = control::controller_step(*params, state, target_mm / mpv, y / mpv);
      run.t_s.push_back(static_cast<double>(k) * run.Ts), run.r_mm.push_back(target_mm), run.y_mm.push_back(y);
      run.u_V.push_back(out.valve_v), run.uc_V.push_back(out.controller_v);
      max_abs_valve_v = std::max(max_abs_valve_v, std::abs(out.valve_v));
      plant_.step(out.valve_v);
      if (abort_after_samples && --abort_after_samples == 0) abort_target->abort();  // the operator, mid-move
    }
    ++moves;
    return run;
  }

  void stop() override { ++stops; }

  struct Switch {
    std::int64_t id;
    bool persist;
    std::string reason;
  };
  std::int64_t loop_set = 1, stored_active = 1;
  std::vector<Switch> switches;
  int excitations = 0, moves = 0, stops = 0;
  double max_abs_valve_v = 0.0;
  commission::CommissionSequence* abort_target = nullptr;
  std::size_t abort_after_samples = 0;  // >0: abort_target is aborted after this many samples of moves

 private:
  plant::HammersteinPlant plant_;
  std::map<std::int64_t, commission::RunningTuning> sets_;
};

}  // namespace epa::testing
