#pragma once
// The diagnosis as a report: the epa-gap-report/1 JSON (docs/formats.md, keys exactly as given there;
// extra keys only added beside them) and the numbers the HTML report draws.
#include <optional>
#include <string>
#include <vector>

#include "core/run.hpp"
#include "diag/axis_change_selection.hpp"
#include "diag/regimes.hpp"
#include "diag/selection.hpp"
#include "diag/whole_move.hpp"

namespace epa::diag {

struct NamedRun {
  std::string name;  // as the user gave it (the file path)
  const core::Run* run = nullptr;
};

struct RunGap {
  std::string name, set;  // set: "train" or "heldout"
  double before_mm = 0, refit_mm = 0, after_mm = 0;
};

struct RegimeRow {
  RegimeShare before;           // nominal model: time share, gap share, RMS
  double refit_gap_mm = 0, after_gap_mm = 0, after_gap_share_pct = 0;
};

struct GapReport {
  Diagnosis diagnosis;
  std::vector<std::string> train_names, heldout_names;
  std::vector<RegimeRow> where;         // on the held-out runs (all runs when cross-validated)
  std::vector<RunGap> per_run;
  ResidualStats residuals_before, residuals_after;
  std::vector<std::string> hints;
  // The run drawn in the HTML report: measured, and the nominal and final models' predictions.
  std::string trace_name;
  std::vector<double> trace_t_s, trace_measured_mm, trace_nominal_mm, trace_final_mm, trace_u_V;
  // The gap over whole moves (whole_move.hpp) and, against a commissioned stick-slip model, what
  // changed since (axis_change_selection.hpp). With a stick-slip model the verdict is judged on
  // whole moves: the measure on which friction shows, and one that no --horizon changes.
  std::optional<WholeMoveGap> whole_move;
  std::optional<AxisChanges> changes;
  bool judged_on_whole_moves() const { return whole_move && whole_move->has_stick_slip; }
};

GapReport build_report(const Diagnosis& diagnosis, const std::vector<NamedRun>& train, const std::vector<NamedRun>& heldout,
                       const RegimeOptions& regime_options = {});

std::string to_json(const GapReport& report);

// One paragraph in words: what the verdict is, and where the gap lies.
std::string verdict_text(const GapReport& report);

}  // namespace epa::diag
