#include "app/simulate_command.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "app/cli_checks.hpp"
#include "app/output_file.hpp"
#include "appliance/tuning_source.hpp"
#include "control/controller.hpp"
#include "core/format.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"
#include "core/units.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"
#include "plant/stick_slip_model.hpp"
#include "report/response_plot.hpp"
#include "report/simulation_case.hpp"
#include "report/table1_report.hpp"
#include "store/trajectory_settings.hpp"
#include "store/tuning_set.hpp"
#include "sim/model_perturbation.hpp"

namespace epa::app {

void add_simulate_command(CLI::App& app, SimulateOptions& o) {
  auto* cmd = app.add_subcommand("simulate", "Closed-loop step responses on a plant model, next to the paper's Table 1");
  cmd->add_option("--controller", o.controllers, "Controllers to run: pp, pp-ngidz, pp-ffidz, pp-traj")->delimiter(',')->capture_default_str();
  cmd->add_option("--steps", o.steps_mm, "Step sizes from rest at --start, mm (negative: towards 0)")->delimiter(',')->capture_default_str();
  cmd->add_option("--start", o.start_mm, "Position every run starts at rest from, mm")->capture_default_str();
  cmd->add_option("--plant", o.plant,
                  "paper (the model: the paper's or --model), physics (pneumatic cylinder and valve) or stick-slip "
                  "(the [stick_slip] model epa identify wrote into --model)")
      ->capture_default_str()->check(CLI::IsMember({"paper", "hammerstein", "physics", "stick-slip"}));
  cmd->add_option("--physics-config", o.physics_config, "Physics plant parameters (epa-pneumatic/1 TOML); default: built in")
      ->check(CLI::ExistingFile);
  cmd->add_option("--gain-factor", o.gain_factor, "Robustness: the plant's gain (B) is this times the model's")
      ->capture_default_str()->check(cli::kPositive);
  cmd->add_option("--break-point-error", o.break_point_error_v,
                  "Robustness: the plant's dead band is wider by this on each side, V (negative: narrower)")->capture_default_str();
  cmd->add_option("--delay", o.delay_samples, "Robustness: samples of transport delay before the valve")
      ->capture_default_str()->check(CLI::Range(std::size_t{0}, sim::kMaxDelaySamples));
  cmd->add_option("--valve-lag", o.valve_lag_s, "Robustness: first-order lag of the valve, s")->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--duration", o.duration_s, "Length of each run, s")->capture_default_str()->check(cli::kPositive);
  cmd->add_option("--Ts", o.Ts, "Sample time, s (default: the model's, 0.005 for the paper)")->check(cli::kPositive);
  cmd->add_option("--lc", o.lc_mm, "FF-IDZ switch-off band l_c, mm")->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--noise", o.noise_mm, "Sensor noise standard deviation, mm")->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--seed", o.seed, "Seed of the sensor noise")->capture_default_str()->check(cli::kSeed);
  cmd->add_option("--model", o.model_path, "Model file (epa-model/1 TOML); default: the paper's eq 9-10")->check(CLI::ExistingFile);
  cmd->add_option("--design", o.design_path, "Controller from an epa-design/1 JSON file; default: the paper's eq 12-13")->check(CLI::ExistingFile);
  cmd->add_option("--out-dir", o.out_dir, "Write each run as an epa-run/1 CSV file here");
  cmd->add_option("--json", o.json_path, "Write the metrics as epa-sim/1 JSON");
  cmd->add_option("--plot", o.plot_path, "Draw the responses as an SVG picture");
  cmd->add_option("--plot-window", o.plot_window_s, "Seconds of each run to draw")->capture_default_str()->check(cli::kPositive);
}

namespace {

nlohmann::json optional_json(std::optional<double> v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

}  // namespace

int run_simulate(const SimulateOptions& o, std::ostream& out, std::ostream& err) {
  auto model_file = appliance::load_model(o.model_path);
  if (!model_file) return err << "epa simulate: " << model_file.error().message << "\n", 1;
  core::HammersteinModel model = model_file->model;
  if (o.Ts > 0.0) model.Ts = o.Ts;
  auto polynomials = appliance::load_controller_polynomials(o.design_path);
  if (!polynomials) return err << "epa simulate: " << polynomials.error().message << "\n", 1;

  std::vector<control::ControllerKind> kinds;
  for (const auto& name : o.controllers) {
    auto kind = control::parse_controller_kind(name);
    if (!kind) return err << "epa simulate: --controller: " << kind.error().message << "\n", 1;
    kinds.push_back(*kind);
  }

  const bool physics = o.plant == "physics", stick_slip = o.plant == "stick-slip";
  if (physics && (o.gain_factor != 1.0 || o.break_point_error_v != 0.0))
    return err << "epa simulate: --gain-factor and --break-point-error perturb the model plant; the physics plant has its own (--physics-config)\n", 1;
  if (stick_slip && (o.gain_factor != 1.0 || o.break_point_error_v != 0.0))
    return err << "epa simulate: --gain-factor and --break-point-error perturb the Hammerstein model plant, not the stick-slip one\n", 1;
  if (stick_slip && !model_file->stick_slip)
    return err << "epa simulate: --plant stick-slip needs a model file with a [stick_slip] table (--model; epa identify writes one)\n", 1;
  if (!physics && !o.physics_config.empty()) return err << "epa simulate: --physics-config applies to --plant physics only\n", 1;
  plant::PneumaticParams physics_params;
  if (!o.physics_config.empty()) {
    auto p = plant::read_pneumatic_file(o.physics_config);
    if (!p) return err << "epa simulate: " << p.error().message << "\n", 1;
    physics_params = *p;
  }
  const core::HammersteinModel plant_model =
      sim::perturbed(model, {.gain_factor = o.gain_factor, .dead_band_widening_v = o.break_point_error_v});
  if (auto s = plant_model.validate(); !s) return err << "epa simulate: the perturbed plant: " << s.error().message << "\n", 1;
  auto make_plant = [&]() -> core::Result<std::unique_ptr<plant::PlantSimulator>> {
    if (physics)
      return plant::make_pneumatic_simulator(physics_params, {.initial_position_mm = o.start_mm, .noise_std_mm = o.noise_mm,
                                                               .seed = o.seed, .Ts = model.Ts});
    if (stick_slip)
      return plant::make_stick_slip_simulator(*model_file->stick_slip, model.Ts, model.mm_per_volt,
                                              {.initial_position_mm = o.start_mm, .noise_std_mm = o.noise_mm,
                                               .seed = o.seed, .stroke_mm = core::kStrokeMm});
    return plant::make_hammerstein_simulator(plant_model, {.initial_position_mm = o.start_mm, .noise_std_mm = o.noise_mm,
                                                           .seed = o.seed, .stroke_mm = core::kStrokeMm});
  };

  // pp-traj arrives while sliding when the model file says a stick-slip model describes the axis.
  store::TrajectorySettings trajectory;
  const auto coast = plant::sliding_arrival_coast_s(*model_file, trajectory.approach_speed_mm_s);
  if (!coast) return err << "epa simulate: " << coast.error().message << "\n", 1;
  trajectory.coast_s = *coast;
  std::vector<report::SimulationCase> cases;
  for (auto kind : kinds) {
    store::TuningSet set;
    set.controller = kind, set.F = polynomials->F, set.G = polynomials->G, set.H = polynomials->H;
    set.dead_zone = model.dead_zone, set.lc_mm = o.lc_mm, set.valve_limit_v = core::paper::kValveLimitV, set.trajectory = trajectory;
    const control::ControllerConfig config = store::controller_config(set, model, 0.0);
    auto params = control::ControllerParams::make(config);
    if (!params) return err << "epa simulate: " << params.error().message << "\n", 1;
    for (double step : o.steps_mm) {
      auto plant = make_plant();
      if (!plant) return err << "epa simulate: " << plant.error().message << "\n", 1;
      auto run = sim::simulate_step_on(**plant, model.mm_per_volt, *params,
                                       {.step_mm = step, .initial_mm = o.start_mm, .duration_s = o.duration_s,
                                        .noise_std_mm = o.noise_mm, .seed = o.seed},
                                       {.delay_samples = o.delay_samples, .lag_s = o.valve_lag_s});
      if (!run) return err << "epa simulate: step " << step << " mm: " << run.error().message << "\n", 1;
      if (kind == control::ControllerKind::kPpFfidz) run->run.set_meta("lc_mm", core::format_number(o.lc_mm));
      cases.push_back({kind, step, std::move(*run)});
    }
  }

  // Streamed, not through a fixed buffer: the model's and the design's sources are free text (a
  // 256-byte buffer cut the line and its newline: "20 s per run,Plant: ...").
  using core::format_number;
  out << "Step responses: model " << model_file->source << ", controller " << polynomials->source << ", Ts = " << format_number(model.Ts)
      << " s, " << format_number(o.duration_s) << " s per run, l_c = " << format_number(o.lc_mm) << " mm, sensor noise "
      << format_number(o.noise_mm) << " mm\n";
  out << "Plant: "
      << (physics ? "physics (" + (o.physics_config.empty() ? std::string("built-in parameters") : o.physics_config) + ")"
                  : std::string(stick_slip ? "the model's stick-slip table" : "the model"))
      << ", from rest at " << format_number(o.start_mm) << " mm; gain x" << format_number(o.gain_factor) << ", dead band "
      << (o.break_point_error_v >= 0 ? "+" : "") << format_number(o.break_point_error_v) << " V each side, delay " << o.delay_samples
      << " samples, valve lag " << format_number(o.valve_lag_s) << " s\n\n";
  report::print_table1_comparison(out, cases);

  if (!o.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.out_dir, ec);
    if (ec) return err << "epa simulate: cannot create " << o.out_dir << ": " << ec.message() << "\n", 1;
    for (const auto& c : cases) {
      char name[96];
      std::snprintf(name, sizeof name, "%s_%gmm.csv", std::string(control::to_string(c.kind)).c_str(), c.step_mm);
      const std::string path = (std::filesystem::path(o.out_dir) / name).string();
      if (auto s = core::write_run_file(path, c.result.run); !s) return err << "epa simulate: " << s.error().message << "\n", 1;
    }
    out << "runs written to " << o.out_dir << "/\n";
  }

  if (!o.json_path.empty()) {
    nlohmann::json j = {{"schema", "epa-sim/1"}, {"Ts", model.Ts}, {"duration_s", o.duration_s},
                        {"plant", physics ? "physics" : stick_slip ? "stick-slip" : "model"}, {"start_mm", o.start_mm}, {"noise_mm", o.noise_mm},
                        {"gain_factor", o.gain_factor}, {"break_point_error_v", o.break_point_error_v},
                        {"delay_samples", o.delay_samples}, {"valve_lag_s", o.valve_lag_s}, {"results", nlohmann::json::array()}};
    for (const auto& c : cases) {
      const auto& m = c.result.metrics;
      j["results"].push_back({{"controller", control::to_string(c.kind)}, {"step_mm", c.step_mm},
                              {"rise_s", optional_json(m.rise_s)}, {"settling_s", optional_json(m.settling_s)},
                              {"ess_mm", m.ess_mm}, {"overshoot_pct", optional_json(m.overshoot_pct)},
                              {"overshoot_mm", optional_json(m.overshoot_pct ? std::optional<double>(*m.overshoot_pct / 100.0 * std::abs(c.step_mm)) : std::nullopt)},
                              {"valve_sign_changes", c.result.valve_sign_changes},
                              {"valve_sign_changes_last_10s", sim::valve_sign_changes_in_last(c.result, 10.0)},
                              {"faults", c.result.faults}});
    }
    if (auto s = write_output(o.json_path, j.dump(1) + "\n", out); !s) return err << "epa simulate: " << s.error().message << "\n", 1;
    out << "metrics written to " << o.json_path << "\n";
  }

  if (!o.plot_path.empty()) {
    const std::string title = "Closed-loop step responses (" + model_file->source + ", Ts = " + core::format_number(model.Ts) + " s)";
    if (auto s = write_output(o.plot_path, report::render_response_plot(cases, model.dead_zone, o.plot_window_s, title), out); !s)
      return err << "epa simulate: " << s.error().message << "\n", 1;
    out << "picture written to " << o.plot_path << "\n";
  }
  return 0;
}

}  // namespace epa::app
