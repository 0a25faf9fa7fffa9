#pragma once
// Simulated axes for the commissioning tests: a plant stepped in the calling thread (no real time),
// tuning sets kept in memory, every switch recorded for the assertions. The experiment runs as the
// appliance's EXCITE mode does (appliance/commissioning_axis.cpp, runtime/excitation_run.cpp): a piston
// outside the guard lines is first moved to the middle with the set that runs and held 3 s; the
// generator's defaults over the soft limits' span (-2..502 mm), 100 mm guards.
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "commission/axis.hpp"
#include "commission/commission_sequence.hpp"
#include "control/controller.hpp"
#include "core/paper_reference.hpp"
#include "ident/excitation.hpp"
#include "plant/hammerstein_plant.hpp"

namespace epa::testing {

// `Plant` has measured_mm() (the sensor at k) and step(valve_v) (holds it over one sample, to k+1).
template <typename Plant>
class SimulatedAxisOn : public commission::Axis {
 public:
  // `running` is the set (with its model) the loop runs at first, id 1.
  SimulatedAxisOn(Plant plant, commission::RunningTuning running) : plant_(std::move(plant)) {
    running.set.id = 1;
    running.model.id = 1;
    sets_[1] = running;
  }

  double position_mm() override { return plant_.measured_mm(); }
  double setpoint_min_mm() const override { return 20.0; }
  double setpoint_max_mm() const override { return 480.0; }

  core::Result<core::Run> excite(const commission::ExcitationRequest& r, const std::atomic<bool>& abort) override {
    ++excitations;
    if (const double y = plant_.measured_mm(); y < kSoftMinMm + kGuardMm || y > kSoftMaxMm - kGuardMm)
      if (auto placed = move(0.5 * (kSoftMinMm + kSoftMaxMm), 3.0, abort); !placed) return placed.error();
    auto gen = ident::ExcitationGenerator::make({.Ts = kTs, .duration_s = r.duration_s, .amplitude_max_v = r.amplitude_max_v,
                                                 .stroke_mm = kSoftMaxMm - kSoftMinMm, .guard_mm = kGuardMm, .seed = r.seed});
    if (!gen) return gen.error();
    core::Run run;
    run.Ts = kTs;
    run.set_meta("controller", "open-loop");
    run.set_meta("excitation_seed", std::to_string(r.seed));
    for (std::size_t k = 0; !gen->done() && !abort; ++k) {
      const double y = plant_.measured_mm(), u = gen->next(y - kSoftMinMm);
      record(run, k, 0.0, y, u, u);
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
    run.Ts = kTs;
    const double mpv = t.model.model.mm_per_volt;
    for (std::size_t k = 0; k < static_cast<std::size_t>(hold_s / run.Ts) && !abort; ++k) {
      const double y = plant_.measured_mm();
      const auto out = control::controller_step(*params, state, target_mm / mpv, y / mpv);
      record(run, k, target_mm, y, out.valve_v, out.controller_v);
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
  static constexpr double kTs = 0.005, kSoftMinMm = -2.0, kSoftMaxMm = 502.0, kGuardMm = 100.0;

  void record(core::Run& run, std::size_t k, double r, double y, double u, double uc) {
    run.t_s.push_back(static_cast<double>(k) * run.Ts), run.r_mm.push_back(r), run.y_mm.push_back(y);
    run.u_V.push_back(u), run.uc_V.push_back(uc);
    max_abs_valve_v = std::max(max_abs_valve_v, std::abs(u));
  }

  Plant plant_;
  std::map<std::int64_t, commission::RunningTuning> sets_;
};

// The paper's model and tuning (pp-ffidz, eq 12-13), the set an axis runs before commissioning.
inline commission::RunningTuning paper_running_tuning() {
  commission::RunningTuning t;
  t.model.name = "paper";
  t.model.model = core::paper::model();
  t.set.name = "paper";
  t.set.controller = control::ControllerKind::kPpFfidz;
  t.set.F = core::paper::F();
  t.set.G = core::paper::G();
  t.set.H = core::paper::G();
  t.set.dead_zone = t.model.model.dead_zone;
  return t;
}

// The paper's Hammerstein plant (or any model) as the axis, starting at rest at 250 mm.
class SimulatedAxis final : public SimulatedAxisOn<plant::HammersteinPlant> {
 public:
  SimulatedAxis(const core::HammersteinModel& plant_model, commission::RunningTuning running)
      : SimulatedAxisOn(*plant::HammersteinPlant::make(plant_model, {.initial_position_mm = 250.0, .noise_std_mm = 0.05}),
                        std::move(running)) {}
};

}  // namespace epa::testing
