#include "app/simulate_command.hpp"

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "app/output_file.hpp"
#include "app/response_plot.hpp"
#include "app/simulation_case.hpp"
#include "app/table1_report.hpp"
#include "app/tuning_source.hpp"
#include "control/controller.hpp"
#include "core/format.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"

namespace epa::app {

void add_simulate_command(CLI::App& app, SimulateOptions& o) {
  auto* cmd = app.add_subcommand("simulate", "Closed-loop step responses on a plant model, next to the paper's Table 1");
  cmd->add_option("--controller", o.controllers, "Controllers to run: pp, pp-ngidz, pp-ffidz")->delimiter(',')->capture_default_str();
  cmd->add_option("--steps", o.steps_mm, "Step sizes from rest at 0 mm, mm")->delimiter(',')->capture_default_str();
  cmd->add_option("--duration", o.duration_s, "Length of each run, s")->capture_default_str()->check(CLI::PositiveNumber);
  cmd->add_option("--Ts", o.Ts, "Sample time, s (default: the model's, 0.005 for the paper)")->check(CLI::PositiveNumber);
  cmd->add_option("--lc", o.lc_mm, "FF-IDZ switch-off band l_c, mm")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--noise", o.noise_mm, "Sensor noise standard deviation, mm")->capture_default_str()->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", o.seed, "Seed of the sensor noise")->capture_default_str();
  cmd->add_option("--model", o.model_path, "Model file (epa-model/1 TOML); default: the paper's eq 9-10")->check(CLI::ExistingFile);
  cmd->add_option("--design", o.design_path, "Controller from an epa-design/1 JSON file; default: the paper's eq 12-13")->check(CLI::ExistingFile);
  cmd->add_option("--out-dir", o.out_dir, "Write each run as an epa-run/1 CSV file here");
  cmd->add_option("--json", o.json_path, "Write the metrics as epa-sim/1 JSON");
  cmd->add_option("--plot", o.plot_path, "Draw the responses as an SVG picture");
  cmd->add_option("--plot-window", o.plot_window_s, "Seconds of each run to draw")->capture_default_str()->check(CLI::PositiveNumber);
}

namespace {

nlohmann::json optional_json(std::optional<double> v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

}  // namespace

int run_simulate(const SimulateOptions& o, std::ostream& out, std::ostream& err) {
  auto model_file = load_model(o.model_path);
  if (!model_file) return err << "epa simulate: " << model_file.error().message << "\n", 1;
  core::HammersteinModel model = model_file->model;
  if (o.Ts > 0.0) model.Ts = o.Ts;
  auto polynomials = load_controller_polynomials(o.design_path);
  if (!polynomials) return err << "epa simulate: " << polynomials.error().message << "\n", 1;

  std::vector<control::ControllerKind> kinds;
  for (const auto& name : o.controllers) {
    auto kind = control::parse_controller_kind(name);
    if (!kind) return err << "epa simulate: --controller: " << kind.error().message << "\n", 1;
    kinds.push_back(*kind);
  }

  std::vector<SimulationCase> cases;
  for (auto kind : kinds) {
    control::ControllerConfig config{.kind = kind, .F = polynomials->F, .G = polynomials->G, .H = polynomials->H,
                                     .dead_zone = model.dead_zone, .lc_v = o.lc_mm / model.mm_per_volt,
                                     .valve_limit_v = core::paper::kValveLimitV, .safe_valve_v = 0.0};
    auto params = control::ControllerParams::make(config);
    if (!params) return err << "epa simulate: " << params.error().message << "\n", 1;
    for (double step : o.steps_mm) {
      auto run = sim::simulate_step(model, *params, {.step_mm = step, .initial_mm = 0.0, .duration_s = o.duration_s,
                                                     .noise_std_mm = o.noise_mm, .seed = o.seed});
      if (!run) return err << "epa simulate: step " << step << " mm: " << run.error().message << "\n", 1;
      if (kind == control::ControllerKind::kPpFfidz) run->run.set_meta("lc_mm", core::format_number(o.lc_mm));
      cases.push_back({kind, step, std::move(*run)});
    }
  }

  char summary[256];
  std::snprintf(summary, sizeof summary, "Step responses: model %s, controller %s, Ts = %g s, %g s per run, l_c = %g mm, sensor noise %g mm\n\n",
                model_file->source.c_str(), polynomials->source.c_str(), model.Ts, o.duration_s, o.lc_mm, o.noise_mm);
  out << summary;
  print_table1_comparison(out, cases);

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
    nlohmann::json j = {{"schema", "epa-sim/1"}, {"Ts", model.Ts}, {"duration_s", o.duration_s}, {"results", nlohmann::json::array()}};
    for (const auto& c : cases) {
      const auto& m = c.result.metrics;
      j["results"].push_back({{"controller", control::to_string(c.kind)}, {"step_mm", c.step_mm},
                              {"rise_s", optional_json(m.rise_s)}, {"settling_s", optional_json(m.settling_s)},
                              {"ess_mm", m.ess_mm}, {"overshoot_pct", optional_json(m.overshoot_pct)}});
    }
    if (auto s = write_output(o.json_path, j.dump(1) + "\n", out); !s) return err << "epa simulate: " << s.error().message << "\n", 1;
    out << "metrics written to " << o.json_path << "\n";
  }

  if (!o.plot_path.empty()) {
    const std::string title = "Closed-loop step responses (" + model_file->source + ", Ts = " + core::format_number(model.Ts) + " s)";
    if (auto s = write_output(o.plot_path, render_response_plot(cases, model.dead_zone, o.plot_window_s, title), out); !s)
      return err << "epa simulate: " << s.error().message << "\n", 1;
    out << "picture written to " << o.plot_path << "\n";
  }
  return 0;
}

}  // namespace epa::app
