#include "app/identify_command.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "app/cli_checks.hpp"
#include "app/model_scope.hpp"
#include "app/output_file.hpp"
#include "appliance/store_save.hpp"
#include "core/format.hpp"
#include "core/model_file.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"
#include "diag/stick_slip_spread.hpp"
#include "ident/hammerstein_identification.hpp"
#include "ident/order_selection.hpp"
#include "ident/ramp_reading.hpp"
#include "ident/stick_slip_fit.hpp"
#include "report/identify_report.hpp"
#include "store/model_record.hpp"
#include "store/store_file.hpp"

namespace epa::app {

using core::format_number;

void add_identify_command(CLI::App& app, IdentifyOptions& o) {
  auto* cmd = app.add_subcommand(
      "identify", "Identify the plant (dead zone + ARX, the paper's section 2.2) from open-loop run files");
  cmd->add_option("runs", o.runs, "Estimation runs (epa-run/1 CSV, e.g. from epa excite)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--validate", o.validate, "Validation runs: scored, never fitted (give one: the order rule needs it)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--na", o.na, "Order of A: n or a range lo:hi to search")->capture_default_str();
  cmd->add_option("--nb", o.nb, "Number of B coefficients: n or lo:hi")->capture_default_str();
  cmd->add_option("--nk", o.nk, "Input delay in samples (>= 1): n or lo:hi")->capture_default_str();
  cmd->add_option("--out", o.out_path, "Write the identified model (epa-model/1 TOML) for epa design/simulate --model");
  cmd->add_option("--save", o.save_name, "Save the model under this name into the tuning store, with its fit figures");
  cmd->add_option("--db", o.db_path, "The tuning store for --save")->capture_default_str();
  cmd->add_option("--plot", o.plot_path, "Draw measured vs model output of the validation runs as an SVG picture");
  cmd->add_option("--seed", o.seed, "Seed of the particle swarm (same seed, same data: same model)")->capture_default_str()->check(cli::kSeed);
  cmd->add_option("--particles", o.particles, "Particles in the swarm")->capture_default_str()->check(CLI::Range(2u, 10000u));
  cmd->add_option("--generations", o.generations, "Swarm generations")->capture_default_str()->check(CLI::Range(1u, 100000u));
  cmd->add_option("--m-l", o.m_l, "Normalisation: the left slope m_l the model is scaled to (the data fix only m B)")
      ->capture_default_str()->check(cli::kPositive);
  cmd->add_option("--tolerance", o.tolerance_pct, "Order rule: fits within this many points of the best count as equal")
      ->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--mm-per-volt", o.mm_per_volt, "Sensor scale of the model's output y")->capture_default_str()->check(cli::kPositive);
  cmd->add_option("--criterion", o.criterion,
                  "simulation: refine A, B and the dead zone on the free-run simulation error, break points within "
                  "the ramps' dead band; one-step: the swarm's least-squares (one-step prediction) fit alone")
      ->capture_default_str()->check(CLI::IsMember({"simulation", "one-step"}));
  cmd->add_option("--window", o.window_s, "Simulation criterion: restart the simulation from the measured position every "
                                          "this many seconds (0: whole runs)")
      ->capture_default_str()->check(cli::kNonNegative);
  cmd->add_option("--break-points", o.break_points,
                  "Simulation criterion: ramps: keep each break point between where the ramps start the piston from "
                  "rest and where it stops on the way back; free: wherever the simulation error puts it")
      ->capture_default_str()->check(CLI::IsMember({"ramps", "free"}));
  cmd->add_flag("!--no-stick-slip", o.stick_slip,
               "Skip the stick-slip model (the model for simulating a pneumatic axis, fitted after the Hammerstein one)");
  cmd->add_option("--stroke", o.stroke_mm, "Stroke, mm (samples at an end stop are left out)")->capture_default_str()->check(cli::kPositive);
}

namespace {

constexpr const char* kFormatHint =
    "epa identify reads epa-run/1 files: columns t_s, y_mm, u_V, uniformly sampled at Ts; see docs/formats.md";

// Reads, splits at the end stops and checks one group of runs; the first run fixes Ts.
core::Result<std::vector<report::IdentifiedRun>> load_runs(const std::vector<std::string>& paths, std::optional<double>& Ts,
                                                   const IdentifyOptions& o, bool estimation, std::ostream& out) {
  std::vector<report::IdentifiedRun> runs;
  for (const auto& path : paths) {
    auto run = core::read_run_file(path, Ts);
    if (!run) {
      const std::string same_Ts = Ts ? "; all runs must share the first run's Ts = " + format_number(*Ts) + " s" : "";
      return core::Error{run.error().code, run.error().message + " (" + kFormatHint + same_Ts + ")"};
    }
    if (!Ts) Ts = run->Ts;
    report::IdentifiedRun r{path, std::move(*run), {}};
    ident::SegmentReport report;
    r.segments = ident::split_run(r.run, path, {.mm_per_volt = o.mm_per_volt, .stroke_mm = o.stroke_mm}, &report);
    const ident::ExcitationCheck check{.need_both_directions = estimation};
    if (auto s = ident::check_excitation(r.segments, path, check, o.mm_per_volt); !s) return s.error();
    char buf[320];
    std::snprintf(buf, sizeof buf, "  %-11s %s: %zu samples (%g s), %zu segment(s)", estimation ? "estimation" : "validation",
                  path.c_str(), r.run.size(), r.run.duration_s(), r.segments.size());
    out << buf;
    if (report.samples_at_stops + report.samples_in_short > 0)
      out << "; " << report.samples_at_stops + report.samples_in_short
          << " samples at or between end stops left out (the model is linear only inside the stroke)";
    if (const auto c = r.run.meta("controller"); !c.empty() && c != "open-loop")
      out << "; closed-loop run (" << c << "): the controller correlates u with the noise, expect some bias";
    out << "\n";
    runs.push_back(std::move(r));
  }
  return runs;
}

std::vector<ident::Segment> all_segments(const std::vector<report::IdentifiedRun>& runs) {
  std::vector<ident::Segment> s;
  for (const auto& r : runs) s.insert(s.end(), r.segments.begin(), r.segments.end());
  return s;
}

core::Result<ident::ArxOrders> nesting_orders(const ident::OrderSearch& s) {
  if (s.na.lo < 0) return core::invalid_argument("--na must be >= 0");
  if (s.nb.lo < 1) return core::invalid_argument("--nb must be >= 1");
  if (s.nk.lo < 1) return core::invalid_argument("--nk must be >= 1: y(k) is read before u(k) is applied");
  // A, B of every candidate fit inside this one, so the dead zone it finds suits all of them.
  const ident::ArxOrders n{.na = s.na.hi, .nb = s.nb.hi + s.nk.hi - s.nk.lo, .nk = s.nk.lo};
  if (auto v = n.validate(); !v)
    return core::invalid_argument("--na/--nb/--nk: the search reaches " + v.error().message + ": narrow the ranges");
  return n;
}

void print_dead_band(std::ostream& out, const ident::DeadBandReading& band) {
  out << "\nDead band read off the slow ramps (the piston moves from rest on the way out, stops on the way back):\n";
  if (band.ramps.empty())
    out << "  no slow ramps in the estimation runs: the break points are bounded by the commands only\n";
  auto volts = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%+.3f V", v);
    return std::isnan(v) ? std::string("(not seen)") : std::string(buf);
  };
  for (const auto& r : band.ramps) {
    char buf[300];
    std::snprintf(buf, sizeof buf, "  %s at %.2f s, towards %s up to %+.3f V: starts at %s, stops at %s\n", r.segment.c_str(),
                  r.t_s, r.direction > 0 ? "+" : "-", r.peak_v, volts(r.start_v).c_str(), volts(r.stop_v).c_str());
    out << buf;
  }
  for (const auto* side : {&band.right, &band.left}) {
    if (!*side) continue;
    char buf[200];
    std::snprintf(buf, sizeof buf, "  %s break point kept in [%+.3f, %+.3f] V\n", side == &band.right ? "right" : "left",
                  (*side)->lo_v, (*side)->hi_v);
    out << buf;
  }
}

core::Result<ident::OrderSearch> order_search(const IdentifyOptions& o) {
  const auto na = ident::parse_order_range(o.na, "--na");
  const auto nb = ident::parse_order_range(o.nb, "--nb");
  const auto nk = ident::parse_order_range(o.nk, "--nk");
  for (const auto* r : {&na, &nb, &nk})
    if (!*r) return r->error();
  return ident::OrderSearch{.na = *na, .nb = *nb, .nk = *nk, .tolerance_pct = o.tolerance_pct};
}

// Step 1's settings: the dead zone by the swarm, with the ARX part of the nesting order solved
// inside every evaluation; its progress lines go to `err`.
ident::IdentificationOptions identification_options(const IdentifyOptions& o, const ident::OrderSearch& search,
                                                    const ident::ArxOrders& nesting, double Ts, std::ostream& err) {
  ident::IdentificationOptions options;
  options.search = search;
  options.swarm.orders = nesting;
  options.swarm.seed = o.seed;
  options.swarm.particles = o.particles;
  options.swarm.generations = o.generations;
  options.swarm.m_l = o.m_l;
  options.swarm.progress_every = std::max(1u, o.generations / 6);
  options.swarm.progress = [&err](const ident::FitProgress& p) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "  generation %u/%u: V = %.4e, b_r = %.4f V, b_l = %.4f V, m_r/m_l = %.4f (%zu fits)\n",
                  p.generation, p.generations, p.best_loss, p.best.b_r, p.best.b_l, p.best.m_r / p.best.m_l, p.evaluations);
    err << buf << std::flush;
  };
  options.criterion = o.criterion == "simulation" ? ident::FitCriterion::kSimulation : ident::FitCriterion::kOneStep;
  options.window_s = o.window_s;
  options.ramp_band = o.break_points == "ramps";
  options.Ts = Ts;
  options.mm_per_volt = o.mm_per_volt;
  return options;
}

void print_swarm_header(std::ostream& out, const IdentifyOptions& o, const ident::ArxOrders& nesting) {
  out << "\nDead zone: particle swarm (pagmo2 PSO, seed " << o.seed << ", " << o.particles << " particles x "
      << o.generations << " generations) over m_r/m_l, b_r, b_l, with ARX " << nesting.to_string()
      << " by least squares inside each evaluation, then a compass-search polish\n"
      << std::flush;  // the progress lines go to err meanwhile
}

void print_order_selection(std::ostream& out, const IdentifyOptions& o, const ident::Identification& identified) {
  if (o.criterion == "simulation") {
    if (identified.dead_band) print_dead_band(out, *identified.dead_band);
    out << "\nRefinement: every order's A, B and dead zone moved to minimise the free-run simulation error "
        << (o.window_s > 0.0 ? "(restarted from the measured position every " + format_number(o.window_s) + " s)"
                             : std::string("over whole runs"))
        << " (Levenberg-Marquardt), starting from least squares on the swarm's dead zone"
        << (identified.dead_band ? "" : "; break points free") << "\n";
    out << "\nOrder selection (refined models; fit % = 100 (1 - |y - yhat| / |y - mean y|), pooled over runs; "
           "loss V: the simulation error):\n";
  } else {
    out << "\nOrder selection (ARX on u_d = dead zone(u); fit % = 100 (1 - |y - yhat| / |y - mean y|), pooled over runs):\n";
  }
  out << ident::format_order_table(identified.selection) << "Recommended " << identified.selection.reason << "\n";
}

// The stick-slip model fitted from the Hammerstein model and printed, when not --no-stick-slip.
core::Result<std::optional<ident::StickSlipIdentification>> fit_stick_slip(const IdentifyOptions& o, const std::vector<ident::Segment>& est,
                                                                          const std::vector<ident::Segment>& val,
                                                                          const core::HammersteinModel& model, int nk,
                                                                          const report::ModelFitSummary& summary, std::ostream& out) {
  if (!o.stick_slip) return std::optional<ident::StickSlipIdentification>{};
  out << "\nStick-slip model (plant/stick_slip_model.hpp: flow dead zone, air spring, sliding and breakaway "
         "friction, spool lag, dead time), fitted on the free-run simulation error (BOBYQA) from the model above:\n"
      << std::flush;
  ident::StickSlipFitOptions fit_options;
  fit_options.Ts = model.Ts;
  fit_options.mm_per_volt = o.mm_per_volt;
  auto fitted = ident::identify_stick_slip(est, val, model, nk, fit_options);
  if (!fitted) return fitted.error();
  report::print_stick_slip(out, *fitted, summary);
  return std::optional(std::move(*fitted));
}

// The model file's and the store's `source`: orders, runs, the fit that scores it, the seed.
std::string model_source(const IdentifyOptions& o, const ident::ArxOrders& chosen, const report::ModelFitSummary& summary,
                         const std::optional<ident::StickSlipIdentification>& stick_slip) {
  std::string runs_text;
  for (const auto& r : o.runs) runs_text += (runs_text.empty() ? "" : ", ") + r;
  char source[640];
  const char* scored = summary.validated ? "validation" : "estimation";
  const int used = std::snprintf(source, sizeof source, "epa identify: %s from %s; %s free-run fit %.2f %%; PSO seed %llu%s",
                                 chosen.to_string().c_str(), runs_text.c_str(), scored,
                                 summary.validated ? summary.validation.simulation_pct : summary.estimation.simulation_pct,
                                 static_cast<unsigned long long>(o.seed),
                                 o.criterion == "simulation" ? ", refined on the simulation error" : "");
  if (stick_slip && used > 0 && static_cast<std::size_t>(used) < sizeof source)
    std::snprintf(source + used, sizeof source - static_cast<std::size_t>(used), "; stick-slip model: %s free-run fit %.2f %%",
                  scored, summary.validated ? stick_slip->validation_pct : stick_slip->estimation_pct);
  return source;
}

core::Status save_identified(const IdentifyOptions& o, const core::ModelFile& model_file, const ident::ArxOrders& chosen,
                             const report::ModelFitSummary& summary,
                             const std::optional<ident::StickSlipIdentification>& stick_slip, std::ostream& out) {
  const nlohmann::json fit_json = {
      {"orders", chosen.to_string()}, {"runs", o.runs}, {"validation_runs", o.validate},
      {"estimation", {{"one_step_pct", summary.estimation.one_step_pct}, {"simulation_pct", summary.estimation.simulation_pct}}},
      {"validation", summary.validated ? nlohmann::json{{"one_step_pct", summary.validation.one_step_pct},
                                                        {"simulation_pct", summary.validation.simulation_pct}}
                                       : nlohmann::json(nullptr)},
      {"pso_seed", o.seed}, {"criterion", o.criterion},
      {"stick_slip", stick_slip ? report::stick_slip_json(*stick_slip, summary.validated) : nlohmann::json(nullptr)}};
  auto id = appliance::save_model(o.db_path, store::model_record_of(model_file, o.save_name, fit_json.dump()));
  if (!id) return id.error();
  out << "model saved as '" << o.save_name << "' (id " << *id << ") in " << o.db_path << "\n";
  return core::ok();
}

std::vector<const core::Run*> runs_of(const std::vector<report::IdentifiedRun>& runs) {
  std::vector<const core::Run*> out;
  for (const auto& r : runs) out.push_back(&r.run);
  return out;
}

// How far the stick-slip model's terms move over 15 s parts of the validation runs
// (app/model_scope.hpp): epa diagnose names a change of the axis only beyond it. None without
// validation runs.
std::optional<core::StickSlipSpread> spread_on_validation(const core::StickSlipParams& params,
                                                          const std::vector<report::IdentifiedRun>& validation, double Ts,
                                                          const std::array<double, 2>& drive, std::ostream& out) {
  if (validation.empty()) return std::nullopt;
  const auto spread = app::model_spread(params, Ts, runs_of(validation), drive);
  out << "  its terms over " << diag::kSpreadPartS << " s parts of the validation runs spread by: friction x"
      << core::format_number(std::round(std::exp(spread.friction_log_ratio) * 100.0) / 100.0) << ", flow gain x"
      << core::format_number(std::round(std::exp(spread.flow_gain_log_ratio) * 100.0) / 100.0) << ", break points "
      << core::format_number(std::round(spread.break_v * 1000.0) / 1000.0) << " V, spool lag "
      << core::format_number(std::round(spread.spool_lag_s * 1e4) / 10.0) << " ms, dead time " << spread.delay_samples
      << " samples (epa diagnose names a change of the axis only beyond these)\n";
  return spread;
}

}  // namespace

int run_identify(const IdentifyOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&](const std::string& message) { return err << "epa identify: " << message << "\n", 1; };
  const auto search = order_search(o);
  if (!search) return fail(search.error().message);
  const auto nesting = nesting_orders(*search);
  if (!nesting) return fail(nesting.error().message);
  // A store that --save cannot use is said before the fit, not after it with the model file written.
  if (!o.save_name.empty())
    if (auto db = store::open_existing_store(o.db_path); !db) return fail("--save: " + db.error().message);

  std::optional<double> Ts;
  out << "Runs:\n";
  auto est = load_runs(o.runs, Ts, o, true, out);
  if (!est) return fail(est.error().message);
  auto val = load_runs(o.validate, Ts, o, false, out);
  if (!val) return fail(val.error().message);
  const auto est_segments = all_segments(*est), val_segments = all_segments(*val);

  print_swarm_header(out, o, *nesting);
  auto identified = ident::identify_hammerstein(est_segments, val_segments, identification_options(o, *search, *nesting, *Ts, err));
  if (!identified) return fail(identified.error().message);
  print_order_selection(out, o, *identified);
  ident::HammersteinFit fit = std::move(identified->fit);
  fit.evaluations += identified->swarm_evaluations;
  const ident::ArxOrders chosen = fit.arx.model.orders;
  const core::HammersteinModel model = fit.model(*Ts, o.mm_per_volt);
  if (auto s = model.validate(); !s) return fail("the identified model is not valid: " + s.error().message);
  const report::ModelFitSummary summary = report::summarise_fit(fit, est_segments, val_segments, identified->selection.first);
  report::print_identified_model(out, fit, model, summary, o.m_l);
  const auto stick_slip = fit_stick_slip(o, est_segments, val_segments, model, chosen.nk, summary, out);
  if (!stick_slip) return fail(stick_slip.error().message);
  const std::optional<core::StickSlipParams> stick_slip_params =  // what the model file and the plot take
      *stick_slip ? std::optional((*stick_slip)->fit.params) : std::nullopt;

  // What the model file holds is what the store keeps (--out, --save): the same model either way.
  core::ModelFile model_file{model, model_source(o, chosen, summary, *stick_slip)};
  if (!o.out_path.empty() || !o.save_name.empty()) {
    model_file.stick_slip = stick_slip_params;
    model_file.axis_model = *stick_slip ? report::axis_model_verdict(**stick_slip, summary) : core::AxisModel::kHammerstein;
    model_file.identified_drive_v = identified_drive_v(runs_of(*est));
    model_file.stick_slip_spread =
        stick_slip_params ? spread_on_validation(*stick_slip_params, *val, model.Ts, *model_file.identified_drive_v, out) : std::nullopt;
  }
  if (!o.out_path.empty()) {
    if (auto s = core::write_model_file(o.out_path, model_file); !s) return fail(s.error().message);
    out << "\nmodel written to " << o.out_path << "\n";
  }
  if (!o.save_name.empty())
    if (auto s = save_identified(o, model_file, chosen, summary, *stick_slip, out); !s) return fail("--save: " + s.error().message);
  if (!o.plot_path.empty()) {
    const auto& shown = val->empty() ? *est : *val;
    if (auto s = write_output(o.plot_path, report::render_identification_plot(shown, fit, model, !val->empty(), stick_slip_params), out);
        !s)
      return fail(s.error().message);
    out << "picture written to " << o.plot_path << "\n";
  }
  return 0;
}

}  // namespace epa::app
