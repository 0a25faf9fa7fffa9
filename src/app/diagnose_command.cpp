#include "app/diagnose_command.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <functional>
#include <map>
#include <optional>

#include "app/cli_checks.hpp"
#include "app/output_file.hpp"
#include "core/format.hpp"
#include "core/model_file.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"
#include "diag/gap_report.hpp"
#include "diag/selection.hpp"
#include "diag/windowed_gap.hpp"
#include "plant/stick_slip_model.hpp"
#include "report/diagnose_report.hpp"

namespace epa::app {

using core::format_number;

void add_diagnose_command(CLI::App& app, DiagnoseOptions& o) {
  auto* cmd = app.add_subcommand("diagnose",
                                 "Sim-to-real gap: where simulated and recorded runs disagree, which unmodelled effect explains it, "
                                 "and how far it shrinks (epa-gap-report/1)");
  cmd->add_option("runs", o.runs, "Training runs (epa-run/1 CSV)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--holdout", o.holdout, "Held-out runs: scored, never fitted (none: cross-validate by run)")->check(CLI::ExistingFile);
  cmd->add_option("--model", o.model_path, "Nominal model (epa-model/1 TOML); default: the paper's eq 9-10")->check(CLI::ExistingFile);
  cmd->add_option("--horizon", o.horizon, "Samples between restarts from the measured state")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_option("--json", o.json_path, "Write the epa-gap-report/1 JSON here ('-': standard output)");
  cmd->add_option("--report", o.report_path, "Write the HTML report here");
  cmd->add_option("--effects", o.effects, "Candidate effects (default: all eight)")->delimiter(',');
  cmd->add_option("--stroke", o.stroke_mm, "Stroke, mm (end stops)")->capture_default_str()->check(cli::kPositive);
}

namespace {

constexpr std::size_t kMinSamples = 200;  // 1 s at 5 ms: fewer cannot tell an effect from noise

core::Result<std::vector<core::Run>> load(const std::vector<std::string>& paths, double Ts, std::size_t horizon) {
  std::vector<core::Run> runs;
  for (const auto& path : paths) {
    auto run = core::read_run_file(path, Ts);
    if (!run)
      return core::Error{run.error().code, run.error().message + " (epa diagnose reads epa-run/1 files with Ts equal to the model's, " +
                                               format_number(Ts) + " s; see docs/formats.md)"};
    if (run->size() < std::max(kMinSamples, 2 * horizon))
      return core::invalid_argument(path + ": only " + std::to_string(run->size()) + " samples; the diagnosis needs at least " +
                                    std::to_string(std::max(kMinSamples, 2 * horizon)) + " (and two windows of --horizon)");
    runs.push_back(std::move(*run));
  }
  return runs;
}

// The gap over whole moves and, against a model file's stick-slip model, what changed since
// commissioning (diag/whole_move.hpp, diag/axis_change_selection.hpp).
void judge_whole_moves(diag::GapReport& report, const core::ModelFile& file, const std::vector<const core::Run*>& train,
                       const std::vector<const core::Run*>& heldout, double stroke_mm, const std::function<void(const std::string&)>& progress) {
  const auto train_runs = diag::anchor_runs(train), heldout_runs = diag::anchor_runs(heldout);
  const auto scope = diag::judged_scope(file, stroke_mm);
  report.whole_move = diag::whole_move_gap(file, train_runs, heldout_runs, scope, report.diagnosis.noise_std_mm);
  const auto& w = *report.whole_move;
  progress(fmt::format("over whole moves: {} segments from rest ({} left out), law's model {:.3f} mm{}", w.segments, w.segments_left_out,
                       w.hammerstein_heldout.rms_mm(),
                       w.has_stick_slip ? fmt::format(", stick-slip model {:.3f} mm ({:.0f} % explained)", w.stick_slip_heldout.rms_mm(), w.explained_pct)
                                        : std::string()));
  if (!file.stick_slip || heldout.empty()) return;  // changes are scored on held-out runs only
  const diag::ChangeFitData data{*file.stick_slip, file.model.Ts, train_runs, heldout_runs, scope};
  report.changes = diag::select_axis_changes(data, file.stick_slip_spread, w.noise_floor_mm, report.diagnosis.rest_drift.moving);
  const auto& d = report.diagnosis;
  if (std::find(d.effects.begin(), d.effects.end(), plant::EffectKind::kSensorQuantization) != d.effects.end())
    report.changes->sensor_step_mm = d.final_model.effects.param(plant::EffectKind::kSensorQuantization, 0);
  progress(fmt::format("since commissioning: {} change(s) named, held-out gap {:.3f} -> {:.3f} mm", report.changes->accepted.terms.size(),
                       report.changes->commissioned_heldout_mm, report.changes->heldout_after_mm));
}

}  // namespace

int run_diagnose(const DiagnoseOptions& o, std::ostream& out, std::ostream& err) {
  auto fail = [&](const std::string& m) { return err << "epa diagnose: " << m << "\n", 1; };
  core::ModelFile model_file{core::paper::model(), "paper eq 9-10"};
  if (!o.model_path.empty()) {
    auto m = core::read_model_file(o.model_path);
    if (!m) return fail(m.error().message);
    model_file = *m;
  }
  // The stick-slip model runs at the model's Ts: a spring too stiff for it is refused here, by name.
  if (model_file.stick_slip)
    if (auto ss = plant::StickSlipModel::make(*model_file.stick_slip, model_file.model.Ts); !ss)
      return fail(o.model_path + ": [stick_slip] " + ss.error().message);
  diag::ReplayModel nominal{model_file.model, {}, o.stroke_mm};
  if (o.holdout.empty() && o.runs.size() < 2)
    return fail("without --holdout the runs are cross-validated one against the others: give at least 2 runs, or --holdout FILE");
  // A run given twice would be fitted twice, or scored on the very data it was fitted on.
  std::map<std::filesystem::path, std::string> seen;
  for (const auto* files : {&o.runs, &o.holdout})
    for (const auto& file : *files) {
      std::error_code ec;
      const auto [at, fresh] = seen.emplace(std::filesystem::weakly_canonical(file, ec), file);
      if (!fresh) return fail("the run " + file + " is given twice (also as " + at->second + "): each run is fitted or scored once");
    }
  if (o.runs.size() < 4)  // the chance thresholds and tolerances come from 4 training runs and 2 held out
    err << "epa diagnose: note: " << o.runs.size() << " training run(s); the chance thresholds are calibrated on 4, so with "
        << "fewer an effect can be named by chance (record more runs to be sure)\n";
  diag::DiagnosisOptions options;
  options.horizon = o.horizon;
  if (!o.effects.empty()) {
    options.candidates.clear();
    for (const auto& name : o.effects) {
      auto k = plant::parse_effect(name);
      if (!k) return fail("--effects: " + k.error().message);
      options.candidates.push_back(*k);
    }
  }
  auto train = load(o.runs, nominal.model.Ts, o.horizon);
  if (!train) return fail(train.error().message);
  auto held = load(o.holdout, nominal.model.Ts, o.horizon);
  if (!held) return fail(held.error().message);

  std::vector<const core::Run*> train_p, held_p;
  std::vector<diag::NamedRun> train_n, held_n;
  for (std::size_t i = 0; i < train->size(); ++i) train_p.push_back(&(*train)[i]), train_n.push_back({o.runs[i], &(*train)[i]});
  for (std::size_t i = 0; i < held->size(); ++i) held_p.push_back(&(*held)[i]), held_n.push_back({o.holdout[i], &(*held)[i]});

  const auto t0 = std::chrono::steady_clock::now();
  options.progress = [&err, t0](const std::string& line) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    char b[32];
    std::snprintf(b, sizeof b, "  [%5.1f s] ", s);
    err << b << line << "\n" << std::flush;
  };
  out << "Diagnosing " << train_p.size() << " training run(s)" << (held_p.empty() ? " by cross-validation" : "") << ", "
      << held_p.size() << " held-out run(s), horizon " << o.horizon << " samples\n" << std::flush;
  const auto d = diag::diagnose(nominal, train_p, held_p, options);
  auto report = diag::build_report(d, train_n, held_n);
  judge_whole_moves(report, model_file, train_p, held_p, o.stroke_mm, options.progress);
  out << diag::verdict_text(report) << "\n";
  if (!o.json_path.empty()) {
    if (auto s = write_output(o.json_path, diag::to_json(report), out); !s) return fail(s.error().message);
    if (o.json_path != "-") out << "report written to " << o.json_path << "\n";
  }
  if (!o.report_path.empty()) {
    if (auto s = write_output(o.report_path, report::render_diagnosis_html(report), out); !s) return fail(s.error().message);
    out << "HTML report written to " << o.report_path << "\n";
  }
  return 0;
}

}  // namespace epa::app
