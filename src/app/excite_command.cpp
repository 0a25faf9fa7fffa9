#include "app/excite_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/cli_checks.hpp"
#include "app/output_file.hpp"
#include "appliance/tuning_source.hpp"
#include "core/format.hpp"
#include "core/run_file.hpp"
#include "ident/excitation.hpp"
#include "plant/plant_adapter.hpp"
#include "plant/pneumatic_params.hpp"
#include "report/svg_chart.hpp"

namespace epa::app {

void add_excite_command(CLI::App& app, ExciteOptions& o) {
  auto* cmd = app.add_subcommand(
      "excite", "Open-loop identification run on a simulated plant (ramps and pseudo-random pulses) for epa identify");
  cmd->add_option("--out", o.out_path, "Write the run here (epa-run/1 CSV, controller=open-loop)")->required();
  cmd->add_option("--model", o.model_path, "Plant model file (epa-model/1 TOML); default: the paper's eq 9-10")
      ->check(CLI::ExistingFile);
  cmd->add_option("--plant", o.plant, "hammerstein (the model) or physics (pneumatic cylinder and valve)")
      ->capture_default_str()->check(CLI::IsMember({"hammerstein", "physics"}));
  cmd->add_option("--physics-config", o.physics_config,
                  "Physics plant parameters (epa-pneumatic/1 TOML) for --plant physics; default: built in")
      ->check(CLI::ExistingFile);
  cmd->add_option("--sensor-bits", o.sensor_bits, "Physics plant: ADC resolution over 0-10 V (0: none)")
      ->capture_default_str()->check(CLI::Range(0, 24));
  cmd->add_option("--delay", o.delay_samples, "Physics plant: samples of transport delay before the spool (a long line)")
      ->capture_default_str()->check(CLI::Range(0, 32));
  cmd->add_option("--plot", o.plot_path, "Draw the run (position and valve command) as an SVG picture");
  cmd->add_option("--duration", o.duration_s, "Length of the run, s")->capture_default_str()->check(cli::kPositive);
  cmd->add_option("--seed", o.seed, "Seed of the pulse sequence and of the sensor noise")->capture_default_str()->check(cli::kSeed);
  cmd->add_option("--noise", o.noise_mm, "Sensor noise standard deviation, mm")->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--amplitude-max", o.amplitude_max_v, "Largest |valve command|, V (beyond both break points)")
      ->capture_default_str();
  cmd->add_option("--amplitude-min", o.amplitude_min_v, "Smallest pulse level, V (inside the dead band)")->capture_default_str();
  cmd->add_option("--ramp-rate", o.ramp_rate_v_per_s, "Slope of the ramps through the dead band, V/s")->capture_default_str();
  cmd->add_option("--ramp-travel", o.ramp_travel_mm, "A ramp turns back once the piston has moved this far, mm")
      ->capture_default_str();
  cmd->add_option("--guard", o.guard_mm, "Pulses away from the middle end this close to a stroke end, mm")->capture_default_str();
  cmd->add_flag("--centring", o.centring,
                "Pulse signs keep the piston near the middle; default: they sweep the "
                "stroke between the guard lines, which identifies a model that holds across it");
}

namespace {

// The whole run, then the ramps alone (where the piston starts to move shows the break points, as
// in the paper's figure 6).
std::string render_excitation_plot(const core::Run& run, double ramps_end_s, const std::string& title) {
  report::Series y{"measured position", "#000000", run.t_s, run.y_mm, false};
  report::Series u{"valve command", "#1f77b4", run.t_s, run.u_V, false};
  report::Panel position{"position", "time (s)", "position (mm)", {y}, {}, {}, {}, 0.0, 500.0};
  report::Panel valve{"valve command", "time (s)", "valve command (V)", {u}, {}, {}, {}, {}, {}};
  std::vector<report::Panel> panels = {position, valve};
  if (ramps_end_s > 0.0) {
    report::Panel ramp_y{"ramps through the dead band: position", "time (s)", "position (mm)", {y}, {}, 0.0, ramps_end_s, {}, {}};
    report::Panel ramp_u{"ramps through the dead band: valve command", "time (s)", "valve command (V)", {u}, {}, 0.0, ramps_end_s,
                 {}, {}};
    panels.push_back(std::move(ramp_y));
    panels.push_back(std::move(ramp_u));
  }
  return report::render_svg(title, panels, 1, 1100, 260);
}

constexpr std::uint64_t kNoiseStream = 0x6E6F697365ull;  // the noise's own stream: --noise does not change u
constexpr double kPhysicsTs = 0.005;                      // the paper's Ts, as the built-in model's
constexpr double kSensorSpanV = 10.0;                     // the physics plant's sensor: 0-10 V over the stroke

struct ExcitedRun {
  ident::ExcitationResult result;
  std::string source;  // what ran, for the metadata and the report
  double Ts = 0.0;
};

// The experiment on the pneumatic cylinder and valve, at rest in the middle of its stroke with
// both chambers pressurised (the valve centred for a while, as plant-server starts it).
core::Result<ExcitedRun> excite_physics(const ExciteOptions& o, ident::ExcitationOptions eo) {
  plant::PneumaticParams params;  // the defaults, sized like the paper's rig
  if (!o.physics_config.empty()) {
    auto p = plant::read_pneumatic_file(o.physics_config);
    if (!p) return p.error();
    params = *p;
  }
  eo.stroke_mm = params.stroke_mm;
  auto plant = plant::make_pneumatic_simulator(params, {.initial_position_mm = 0.5 * params.stroke_mm,
                                                        .initial_pressure_bar = 3.0,
                                                        .noise_std_mm = o.noise_mm,
                                                        .seed = o.seed ^ kNoiseStream,
                                                        .sensor_bits = o.sensor_bits,
                                                        .command_delay_samples = o.delay_samples,
                                                        .Ts = kPhysicsTs,
                                                        .substeps = 50});
  if (!plant) return plant.error();
  ExcitedRun r;
  r.source = "physics plant (" + (o.physics_config.empty() ? std::string("built-in parameters") : o.physics_config) + ")";
  r.Ts = kPhysicsTs;
  auto result = ident::run_excitation(**plant, params.stroke_mm / kSensorSpanV, eo, o.noise_mm, "epa excite on " + r.source);
  if (!result) return result.error();
  r.result = std::move(*result);
  return r;
}

core::Result<ExcitedRun> excite_model(const ExciteOptions& o, const ident::ExcitationOptions& eo) {
  auto model_file = appliance::load_model(o.model_path);
  if (!model_file) return model_file.error();
  ExcitedRun r;
  r.source = model_file->source;
  r.Ts = model_file->model.Ts;
  auto result = ident::run_excitation(model_file->model, eo, o.noise_mm, "epa excite on " + model_file->source);
  if (!result) return result.error();
  r.result = std::move(*result);
  return r;
}

}  // namespace

int run_excite(const ExciteOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&](const std::string& message) { return err << "epa excite: " << message << "\n", 1; };
  const bool physics = o.plant == "physics";
  if (physics && !o.model_path.empty())
    return fail("--model applies to --plant hammerstein only (the physics plant takes --physics-config)");
  if (!physics && !o.physics_config.empty())
    return fail("--physics-config applies to --plant physics only");
  if (!physics && (o.sensor_bits != 0 || o.delay_samples != 0))
    return fail("--sensor-bits and --delay apply to --plant physics only");

  ident::ExcitationOptions eo;
  eo.duration_s = o.duration_s;
  eo.amplitude_max_v = o.amplitude_max_v;
  eo.amplitude_min_v = o.amplitude_min_v;
  eo.ramp_rate_v_per_s = o.ramp_rate_v_per_s;
  eo.ramp_travel_mm = o.ramp_travel_mm;
  eo.guard_mm = o.guard_mm;
  eo.sweep = !o.centring;
  eo.seed = o.seed;
  auto excited = physics ? excite_physics(o, eo) : excite_model(o, eo);
  if (!excited) return fail(excited.error().message);
  const ident::ExcitationResult& result = excited->result;
  const core::Run& run = result.run;

  const auto [u_min, u_max] = std::minmax_element(run.u_V.begin(), run.u_V.end());
  const auto [y_min, y_max] = std::minmax_element(run.y_mm.begin(), run.y_mm.end());
  char buf[600];
  std::snprintf(buf, sizeof buf,
                "Excitation run: plant %s, Ts = %g s, %g s (%zu samples), seed %llu, sensor noise %g mm\n"
                "  ramps through the dead band: the piston first moved (%g mm) at u = %+.3f V and %+.3f V;\n"
                "    the break points lie just inside these (the piston needs a moment to move %g mm)\n"
                "  pulses: %zu, %zu of them cut short by the %g mm guard; levels %g-%g V\n"
                "  valve command in [%g, %g] V, position in [%.1f, %.1f] mm\n",
                excited->source.c_str(), excited->Ts, o.duration_s, run.size(), static_cast<unsigned long long>(o.seed),
                o.noise_mm, ident::ExcitationGenerator::kMotionThresholdMm, result.ramp_motion_up_v,
                result.ramp_motion_down_v, ident::ExcitationGenerator::kMotionThresholdMm, result.pulses,
                result.pulses_cut, o.guard_mm, o.amplitude_min_v, o.amplitude_max_v, *u_min, *u_max, *y_min, *y_max);
  out << buf;
  if (std::isnan(result.ramp_motion_up_v) || std::isnan(result.ramp_motion_down_v))
    out << "  warning: a ramp reached --amplitude-max without moving the piston: the dead band may be wider than "
           "the amplitude; raise --amplitude-max\n";
  if (result.samples_at_stops > 0)
    out << "  warning: " << result.samples_at_stops
        << " samples with the piston at an end stop (epa identify leaves them out); lower --amplitude-max or raise --guard\n";

  if (auto s = core::write_run_file(o.out_path, run); !s) return fail(s.error().message);
  out << "run written to " << o.out_path << "\n";
  if (!o.plot_path.empty()) {
    if (auto s = write_output(o.plot_path, render_excitation_plot(run, result.ramps_end_s, "Excitation run (" + excited->source + ")"), out);
        !s)
      return fail(s.error().message);
    out << "picture written to " << o.plot_path << "\n";
  }
  return 0;
}

}  // namespace epa::app
