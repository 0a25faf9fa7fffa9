#pragma once
// An axis for the commissioning tests that is not any model the commissioning fits: the physics
// plant (plant/pneumatic_plant.*) with a rig's hidden perturbations, behind a remote I/O path as
// the appliance meets it: the module steps its plant on its own clock, so a command written after a
// reading reaches the valve at the module's next cycle, as in-process, or one cycle later when the
// request misses it (with probability late_probability, in order); the sensor noise has its own seed. Stepped in the calling thread (no real time).
#include <algorithm>
#include <deque>
#include <map>
#include <random>
#include <vector>

#include "commission/axis.hpp"
#include "control/controller.hpp"
#include "ident/excitation.hpp"
#include "plant/pneumatic_plant.hpp"
#include "store/tuning_set.hpp"

namespace epa::testing {

class PhysicsRigAxis final : public commission::Axis {
 public:
  // `running` is the set (with its model) the loop runs at first, id 1.
  PhysicsRigAxis(const plant::PneumaticParams& rig, std::uint64_t noise_seed, double late_probability,
                 commission::RunningTuning running)
      : plant_(*plant::PneumaticPlant::make(rig, {.initial_position_mm = 250.0, .noise_std_mm = 0.05, .seed = noise_seed, .sensor_bits = 15})),
        late_probability_(late_probability),
        io_random_(noise_seed * 7919 + 1) {
    running.set.id = 1;
    running.model.id = 1;
    sets_[1] = running;
  }

  double position_mm() override { return plant_.measured_mm(); }
  double setpoint_min_mm() const override { return 0.0; }
  double setpoint_max_mm() const override { return 500.0; }

  core::Result<core::Run> excite(const commission::ExcitationRequest& r, const std::atomic<bool>& abort) override {
    // As the appliance's EXCITE mode (app/appliance_axis.cpp): a piston outside the guard lines is
    // first moved to the middle with the set that runs and held 3 s; the generator's defaults over
    // the soft limits' span (-2..502 mm), 100 mm guards.
    if (const double y = plant_.measured_mm(); y < 98.0 || y > 402.0)
      if (auto placed = move(250.0, 3.0, abort); !placed) return placed.error();
    auto gen = ident::ExcitationGenerator::make(
        {.duration_s = r.duration_s, .amplitude_max_v = r.amplitude_max_v, .stroke_mm = 504.0, .seed = r.seed});
    if (!gen) return gen.error();
    core::Run run;
    run.Ts = plant_.Ts();
    run.set_meta("controller", "open-loop");
    run.set_meta("excitation_seed", std::to_string(r.seed));
    for (std::size_t k = 0; !gen->done() && !abort; ++k) {
      const double y = plant_.measured_mm(), u = gen->next(y + 2.0);
      record(run, k, 0.0, y, u, u);
      step(u);
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

  core::Status use_set(std::int64_t id, bool, const std::string&) override {
    if (!sets_.contains(id)) return core::invalid_argument("no set " + std::to_string(id));
    loop_set = id;
    return core::ok();
  }

  core::Result<core::Run> move(double target_mm, double hold_s, const std::atomic<bool>& abort) override {
    const auto& t = sets_.at(loop_set);
    auto params = control::ControllerParams::make(store::controller_config(t.set, t.model.model, 0.0));
    if (!params) return params.error();
    control::ControllerState state;
    core::Run run;
    run.Ts = plant_.Ts();
    const double mpv = t.model.model.mm_per_volt;
    for (std::size_t k = 0; k < static_cast<std::size_t>(hold_s / run.Ts) && !abort; ++k) {
      const double y = plant_.measured_mm();
      const auto out = control::controller_step(*params, state, target_mm / mpv, y / mpv);
      record(run, k, target_mm, y, out.valve_v, out.controller_v);
      step(out.valve_v);
    }
    return run;
  }

  void stop() override {
    for (int k = 0; k < 4; ++k) step(0.0);
  }

  std::int64_t loop_set = 1;

 private:
  static void record(core::Run& run, std::size_t k, double r, double y, double u, double uc) {
    run.t_s.push_back(static_cast<double>(k) * run.Ts), run.r_mm.push_back(r), run.y_mm.push_back(y);
    run.u_V.push_back(u), run.uc_V.push_back(uc);
  }

  // The command sent at this sample drives the next step, or (late) the one after.
  void step(double command_v) {
    const bool late = std::bernoulli_distribution(late_probability_)(io_random_);
    in_flight_.push_back({now_ + (late ? 1 : 0), command_v});
    while (!in_flight_.empty() && in_flight_.front().arrives <= now_) valve_v_ = in_flight_.front().command_v, in_flight_.pop_front();
    plant_.step(valve_v_);
    ++now_;
  }

  struct Sent {
    std::uint64_t arrives;
    double command_v;
  };
  plant::PneumaticPlant plant_;
  double late_probability_;
  std::mt19937_64 io_random_;
  std::deque<Sent> in_flight_;
  std::uint64_t now_ = 0;
  double valve_v_ = 0.0;
  std::map<std::int64_t, commission::RunningTuning> sets_;
};

}  // namespace epa::testing
