#include "app/simulate_command.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <sstream>
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
#include "runtime/tuning.hpp"
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
  cmd->add_option("--sensor-bits", o.sensor_bits, "Physics plant: ADC resolution over 0-10 V (0: none)")
      ->capture_default_str()->check(CLI::Range(0, 24));
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

using PlantMaker = std::function<core::Result<std::unique_ptr<plant::PlantSimulator>>()>;

bool physics_plant(const SimulateOptions& o) { return o.plant == "physics"; }
bool stick_slip_plant(const SimulateOptions& o) { return o.plant == "stick-slip"; }

core::Result<std::vector<control::ControllerKind>> controller_kinds(const SimulateOptions& o) {
  std::vector<control::ControllerKind> kinds;
  for (const auto& name : o.controllers) {
    auto kind = control::parse_controller_kind(name);
    if (!kind) return core::invalid_argument("--controller: " + kind.error().message);
    kinds.push_back(*kind);
  }
  return kinds;
}

core::Status check_plant_options(const SimulateOptions& o, const core::ModelFile& model_file) {
  const bool perturbed = o.gain_factor != 1.0 || o.break_point_error_v != 0.0;
  if (physics_plant(o) && perturbed)
    return core::invalid_argument("--gain-factor and --break-point-error perturb the model plant; the physics plant has its own (--physics-config)");
  if (stick_slip_plant(o) && perturbed)
    return core::invalid_argument("--gain-factor and --break-point-error perturb the Hammerstein model plant, not the stick-slip one");
  if (stick_slip_plant(o) && !model_file.stick_slip)
    return core::invalid_argument("--plant stick-slip needs a model file with a [stick_slip] table (--model; epa identify writes one)");
  if (!physics_plant(o) && !o.physics_config.empty()) return core::invalid_argument("--physics-config applies to --plant physics only");
  if (!physics_plant(o) && o.sensor_bits != 0) return core::invalid_argument("--sensor-bits applies to --plant physics only");
  return core::ok();
}

// A fresh plant for every run, at rest at --start: the physics plant, the model file's stick-slip
// model, or the model (perturbed by --gain-factor and --break-point-error).
core::Result<PlantMaker> plant_maker(const SimulateOptions& o, const core::ModelFile& model_file, const core::HammersteinModel& model) {
  plant::PneumaticParams physics_params;
  if (!o.physics_config.empty()) {
    auto p = plant::read_pneumatic_file(o.physics_config);
    if (!p) return p.error();
    physics_params = *p;
  }
  const core::HammersteinModel plant_model =
      sim::perturbed(model, {.gain_factor = o.gain_factor, .dead_band_widening_v = o.break_point_error_v});
  if (auto s = plant_model.validate(); !s) return core::invalid_argument("the perturbed plant: " + s.error().message);
  return PlantMaker([&o, &model_file, model, plant_model, physics_params]() -> core::Result<std::unique_ptr<plant::PlantSimulator>> {
    if (physics_plant(o))
      return plant::make_pneumatic_simulator(physics_params, {.initial_position_mm = o.start_mm, .noise_std_mm = o.noise_mm,
                                                               .seed = o.seed, .sensor_bits = o.sensor_bits, .Ts = model.Ts});
    if (stick_slip_plant(o))
      return plant::make_stick_slip_simulator(*model_file.stick_slip, model.Ts, model.mm_per_volt,
                                              {.initial_position_mm = o.start_mm, .noise_std_mm = o.noise_mm,
                                               .seed = o.seed, .stroke_mm = core::kStrokeMm});
    return plant::make_hammerstein_simulator(plant_model, {.initial_position_mm = o.start_mm, .noise_std_mm = o.noise_mm,
                                                           .seed = o.seed, .stroke_mm = core::kStrokeMm});
  });
}

// The controller of `kind` with the polynomials, the model's dead zone and --lc, as a tuning set
// would make it, and with what the appliance's loop gives it under the default [motion] settings
// (pp-traj: its back-offs within the setpoint range 0-500 mm, its stops judged against the 1 mm
// in-position window), so that a simulated move ends as the appliance's would.
core::Result<control::ControllerParams> controller_params(control::ControllerKind kind, const SimulateOptions& o,
                                                          const appliance::ControllerPolynomials& polynomials,
                                                          const store::TrajectorySettings& trajectory, const core::HammersteinModel& model) {
  store::TuningSet set;
  set.controller = kind, set.F = polynomials.F, set.G = polynomials.G, set.H = polynomials.H;
  set.dead_zone = model.dead_zone, set.lc_mm = o.lc_mm, set.valve_limit_v = core::paper::kValveLimitV, set.trajectory = trajectory;
  runtime::RuntimeConfig loop;
  loop.mm_per_volt = model.mm_per_volt;
  return control::ControllerParams::make(runtime::with_loop_limits(store::controller_config(set, model, 0.0), loop));
}

// Every controller on every step, each on a fresh plant.
core::Result<std::vector<report::SimulationCase>> simulate_cases(const SimulateOptions& o, const std::vector<control::ControllerKind>& kinds,
                                                                 const appliance::ControllerPolynomials& polynomials,
                                                                 const core::ModelFile& model_file, const core::HammersteinModel& model,
                                                                 const PlantMaker& make_plant) {
  // pp-traj arrives while sliding when the model file says a stick-slip model describes the axis.
  store::TrajectorySettings trajectory;
  const auto coast = plant::sliding_arrival_coast_s(model_file, trajectory.approach_speed_mm_s);
  if (!coast) return coast.error();
  trajectory.coast_s = *coast;
  std::vector<report::SimulationCase> cases;
  for (auto kind : kinds) {
    auto params = controller_params(kind, o, polynomials, trajectory, model);
    if (!params) return params.error();
    for (double step : o.steps_mm) {
      auto plant = make_plant();
      if (!plant) return plant.error();
      auto run = sim::simulate_step_on(**plant, model.mm_per_volt, *params,
                                       {.step_mm = step, .initial_mm = o.start_mm, .duration_s = o.duration_s,
                                        .noise_std_mm = o.noise_mm, .seed = o.seed},
                                       {.delay_samples = o.delay_samples, .lag_s = o.valve_lag_s});
      if (!run) {
        std::ostringstream what;
        what << "step " << step << " mm: " << run.error().message;
        return core::Error{run.error().code, what.str()};
      }
      if (kind == control::ControllerKind::kPpFfidz) run->run.set_meta("lc_mm", core::format_number(o.lc_mm));
      cases.push_back({kind, step, std::move(*run)});
    }
  }
  return cases;
}

// Streamed, not through a fixed buffer: the model's and the design's sources are free text (a
// 256-byte buffer cut the line and its newline: "20 s per run,Plant: ...").
void print_setup(std::ostream& out, const SimulateOptions& o, const core::ModelFile& model_file,
                 const appliance::ControllerPolynomials& polynomials, const core::HammersteinModel& model) {
  using core::format_number;
  out << "Step responses: model " << model_file.source << ", controller " << polynomials.source << ", Ts = " << format_number(model.Ts)
      << " s, " << format_number(o.duration_s) << " s per run, l_c = " << format_number(o.lc_mm) << " mm, sensor noise "
      << format_number(o.noise_mm) << " mm\n";
  out << "Plant: "
      << (physics_plant(o) ? "physics (" + (o.physics_config.empty() ? std::string("built-in parameters") : o.physics_config) + ")"
                           : std::string(stick_slip_plant(o) ? "the model's stick-slip table" : "the model"))
      << ", from rest at " << format_number(o.start_mm) << " mm; gain x" << format_number(o.gain_factor) << ", dead band "
      << (o.break_point_error_v >= 0 ? "+" : "") << format_number(o.break_point_error_v) << " V each side, delay " << o.delay_samples
      << " samples, valve lag " << format_number(o.valve_lag_s) << " s\n\n";
}

core::Status write_run_files(const std::string& dir, const std::vector<report::SimulationCase>& cases) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return core::io_error("cannot create " + dir + ": " + ec.message());
  for (const auto& c : cases) {
    char name[96];
    std::snprintf(name, sizeof name, "%s_%gmm.csv", std::string(control::to_string(c.kind)).c_str(), c.step_mm);
    const std::string path = (std::filesystem::path(dir) / name).string();
    if (auto s = core::write_run_file(path, c.result.run); !s) return s;
  }
  return core::ok();
}

std::string sim_json(const SimulateOptions& o, const core::HammersteinModel& model, const std::vector<report::SimulationCase>& cases) {
  nlohmann::json j = {{"schema", "epa-sim/1"}, {"Ts", model.Ts}, {"duration_s", o.duration_s},
                      {"plant", physics_plant(o) ? "physics" : stick_slip_plant(o) ? "stick-slip" : "model"}, {"start_mm", o.start_mm}, {"noise_mm", o.noise_mm},
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
  return j.dump(1) + "\n";
}

}  // namespace

int run_simulate(const SimulateOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&err](const std::string& message) { return err << "epa simulate: " << message << "\n", 1; };
  auto model_file = appliance::load_model(o.model_path);
  if (!model_file) return fail(model_file.error().message);
  core::HammersteinModel model = model_file->model;
  if (o.Ts > 0.0) model.Ts = o.Ts;
  auto polynomials = appliance::load_controller_polynomials(o.design_path);
  if (!polynomials) return fail(polynomials.error().message);
  auto kinds = controller_kinds(o);
  if (!kinds) return fail(kinds.error().message);
  if (auto s = check_plant_options(o, *model_file); !s) return fail(s.error().message);
  auto make_plant = plant_maker(o, *model_file, model);
  if (!make_plant) return fail(make_plant.error().message);
  auto cases = simulate_cases(o, *kinds, *polynomials, *model_file, model, *make_plant);
  if (!cases) return fail(cases.error().message);

  print_setup(out, o, *model_file, *polynomials, model);
  report::print_table1_comparison(out, *cases);
  if (!o.out_dir.empty()) {
    if (auto s = write_run_files(o.out_dir, *cases); !s) return fail(s.error().message);
    out << "runs written to " << o.out_dir << "/\n";
  }
  if (!o.json_path.empty()) {
    if (auto s = write_output(o.json_path, sim_json(o, model, *cases), out); !s) return fail(s.error().message);
    out << "metrics written to " << o.json_path << "\n";
  }
  if (!o.plot_path.empty()) {
    const std::string title = "Closed-loop step responses (" + model_file->source + ", Ts = " + core::format_number(model.Ts) + " s)";
    if (auto s = write_output(o.plot_path, report::render_response_plot(*cases, model.dead_zone, o.plot_window_s, title), out); !s)
      return fail(s.error().message);
    out << "picture written to " << o.plot_path << "\n";
  }
  return 0;
}

}  // namespace epa::app
