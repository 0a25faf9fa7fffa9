// The model-health monitor (diag/model_health.hpp) against the physics plant, faster than real
// time: an axis commissioned by `epa identify` (the model file given) makes moves between random
// targets with pp-traj designed on that model, as the appliance would, each move recorded from its
// start for move_s seconds; after `change_at` moves (32) one physical parameter changes
// (plant/pneumatic_params.hpp keys, as `epa plant-server`'s `physics` lines), and every move is
// handed to the monitor. Prints each state change, then one line per case:
//
//   case friction-x2 seed 1: named static_friction after 6 moves (friction up 92 % since the baseline (...), ratio 1.92), ...
//
//   health_drift MODEL.toml [--case NAME] [--seeds N] [--first-seed S] [--moves N] [--change-at N] [--law pp-traj|pp-ffidz]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "control/controller.hpp"
#include "control/paper_controller.hpp"
#include "core/model_file.hpp"
#include "diag/model_health.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"
#include "plant/stick_slip_model.hpp"
#include "sim/random_moves.hpp"

namespace {

using namespace epa;

struct Change {
  std::string name;
  std::vector<std::pair<std::string, double>> keys;  // set at change_at
  const char* expected;                              // the effect's name, "" for none
  int direction;                                     // the ratio's expected side of 1 (+1 up, -1 down)
};

std::vector<Change> cases() {
  const plant::PneumaticParams d;
  return {
      {"friction-x2", {{"static_friction_n", 2 * d.static_friction_n}, {"coulomb_friction_n", 2 * d.coulomb_friction_n}}, "static_friction", +1},
      {"supply-4.5bar", {{"supply_pressure_bar", 4.5}}, "gain_change", -1},
      {"overlap-0.25V", {{"overlap_pos_v", d.overlap_pos_v - 0.25}}, "deadzone_shift", -1},
      {"spool-x3", {{"spool_time_constant_s", 3 * d.spool_time_constant_s}}, "valve_lag", +1},
      {"null", {}, "", 0},
  };
}

control::ControllerParams law_for(const core::ModelFile& f, control::ControllerKind kind) {
  auto c = control::paper_controller_config(kind);
  if (kind == control::ControllerKind::kPpTraj) {
    c.A = f.model.A;
    c.B = f.model.B;
    c.dead_zone = f.model.dead_zone;
    const auto coast = plant::sliding_arrival_coast_s(f, 50.0 * c.trajectory.approach_speed_v_s);
    c.trajectory.coast_s = coast ? *coast : 0.0;
  }
  auto p = control::ControllerParams::make(c);
  if (!p) {
    std::fprintf(stderr, "health_drift: %s\n", p.error().message.c_str());
    std::exit(1);
  }
  return *p;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The model-health monitor on the physics plant, one change at a time"};
  std::string model_path, only, law = "pp-traj";
  int seeds = 1, first_seed = 1, moves = 70, change_at = 32;
  double move_s = 2.5, noise_mm = 0.1;
  app.add_option("model", model_path, "epa-model/1 file with [stick_slip] (epa identify)")->required();
  app.add_option("--case", only, "one case by name");
  app.add_option("--seeds", seeds, "seeds per case");
  app.add_option("--first-seed", first_seed, "the first seed (seeds run from it on)");
  app.add_option("--moves", moves, "moves per run");
  app.add_option("--change-at", change_at, "the change comes after this many moves");
  app.add_option("--move-s", move_s, "each move's length, s");
  app.add_option("--noise", noise_mm, "sensor noise, mm");
  app.add_option("--law", law, "pp-traj or pp-ffidz");
  diag::HealthConfig hc;
  bool verbose = false, scoped = false;
  app.add_flag("--scoped", scoped, "judge only inside the model's identified drive range");
  app.add_flag("--verbose", verbose, "every judgement's estimates");
  app.add_option("--baseline-moves", hc.baseline_moves, "the monitor's baseline_moves");
  app.add_option("--window-moves", hc.window_moves, "the monitor's window_moves");
  app.add_option("--confirm", hc.confirm_windows, "the monitor's confirm_windows");
  app.add_option("--min-reduction", hc.min_reduction, "the monitor's min_reduction");
  app.add_option("--span", hc.span_s, "the monitor's span_s");
  app.add_option("--spread-margin", hc.spread_margin, "the monitor's spread_margin");
  CLI11_PARSE(app, argc, argv);
  auto file = core::read_model_file(model_path);
  if (!file || !file->stick_slip) {
    std::fprintf(stderr, "health_drift: %s\n", file ? "the model file has no [stick_slip] table" : file.error().message.c_str());
    return 1;
  }
  const auto kind = *control::parse_controller_kind(law);
  const auto params = law_for(*file, kind);
  const double Ts = file->model.Ts;
  int named_right = 0, runs = 0, false_alarms = 0;
  std::vector<int> delays;

  for (const Change& change : cases()) {
    if (!only.empty() && change.name != only) continue;
    for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
      ++runs;
      auto plant = plant::make_pneumatic_simulator({}, {.initial_position_mm = 250.0, .noise_std_mm = noise_mm, .seed = static_cast<std::uint64_t>(seed)});
      auto health = diag::ModelHealth::make(*file->stick_slip, Ts, 500.0, hc, scoped ? file->identified_drive_v : std::nullopt);
      if (!plant || !health) {
        std::fprintf(stderr, "health_drift: %s\n", !plant ? plant.error().message.c_str() : health.error().message.c_str());
        return 1;
      }
      sim::RandomMoves sequence(**plant, params, {.move_s = move_s, .seed = static_cast<std::uint64_t>(seed)});
      int named_after = -1, alarms = 0;
      std::string named_size;
      double named_ratio = 1.0;
      for (int m = 0; m < moves; ++m) {
        if (m == change_at && !change.keys.empty()) {
          auto p = *(*plant)->physics_params();
          for (const auto& [key, value] : change.keys) (void)plant::set_pneumatic_key(p, key, value);
          (void)(*plant)->set_physics_params(p);
        }
        auto [run, hunted] = sequence.next();
        const double from_mm = run.y_mm.front(), to_mm = run.r_mm.back();
        const bool changed = health->add_move(std::move(run), hunted);
        const auto& v = health->verdict();
        if (changed || verbose) {
          std::printf("  %s seed %d move %d (%.0f -> %.0f mm): %s %s %s (since onset %zu; gap %.2f mm, baseline %.2f mm)\n", change.name.c_str(),
                      seed, m + 1, from_mm, to_mm, diag::to_string(v.state), v.effect ? plant::to_string(*v.effect).data() : "", v.size.c_str(),
                      v.moves_since_onset, v.window_gap_mm, v.baseline_gap_mm);
          if (verbose)
            for (const auto& e : v.estimates)
              std::printf("      %-16s ratio %6.3f reduction %5.1f %% %s\n", plant::to_string(e.effect).data(), e.ratio, 100 * e.reduction,
                          e.beyond_tolerance ? "beyond" : "");
        }
        const bool alarm = v.state == diag::HealthState::kDrifting || v.state == diag::HealthState::kUnexplained;
        if (m < change_at || change.keys.empty()) {
          if (alarm && changed) ++alarms;
        } else if (named_after < 0 && v.state == diag::HealthState::kDrifting && v.effect &&
                   plant::to_string(*v.effect) == change.expected) {
          named_after = m + 1 - change_at;
          named_size = v.size;
          named_ratio = v.ratio;
        }
      }
      false_alarms += alarms;
      const auto& v = health->verdict();
      if (change.keys.empty()) {
        std::printf("case %s seed %d: %d false alarm(s) in %d moves; final state %s; %zu fits\n", change.name.c_str(), seed, alarms, moves,
                    diag::to_string(v.state), health->fits());
      } else {
        const bool right_way = named_after >= 0 && (named_ratio - 1.0) * change.direction > 0;
        if (named_after >= 0 && right_way) ++named_right, delays.push_back(named_after);
        std::printf("case %s seed %d: %s%s; at the end: %s %s (ratio %.2f); %d false alarm(s) before the change; %zu fits\n", change.name.c_str(), seed,
                    named_after >= 0 ? ("named " + std::string(change.expected) + " after " + std::to_string(named_after) + " moves (" + named_size +
                                        ", ratio " + std::to_string(named_ratio).substr(0, 4) + ")")
                                           .c_str()
                                     : ("not named (expected " + std::string(change.expected) + ")").c_str(),
                    named_after >= 0 && !right_way ? ", the wrong way" : "", diag::to_string(v.state), v.size.c_str(), v.ratio, alarms, health->fits());
      }
    }
  }
  std::sort(delays.begin(), delays.end());
  std::printf("health drift: %d of %d changes named the right way, median %d moves after the change, latest %d; %d false alarm(s)\n", named_right,
              runs - (only.empty() || only == "null" ? seeds : 0), delays.empty() ? -1 : delays[delays.size() / 2],
              delays.empty() ? -1 : delays.back(), false_alarms);
  return 0;
}
