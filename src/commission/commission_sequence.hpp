#pragma once
// The commissioning sequence: excite -> identify -> design -> verify in simulation ->
// save -> use -> verify on the axis -> keep, or roll back to the previous set at once. An
// experiment whose runs the identified model cannot follow is run once more before the design.
//
// Nothing is left half-done. The new set is stored but the store's active set changes only when the
// axis verification passed (Axis::use_set persist), so a restart mid-way comes up on the previous
// set; every failure or abort puts the valve safe (Axis::stop) and, once the new set ran, switches
// the loop back to the previous one. Each step is logged with its reason; the switches are audited
// by the axis. Runs in the calling thread; abort() and progress() may be called from any other.
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "commission/axis.hpp"
#include "commission/commission_spec.hpp"
#include "commission/move_acceptance.hpp"
#include "commission/simulated_verification.hpp"
#include "control/pole_placement_design.hpp"
#include "core/hammerstein_model.hpp"
#include "core/model_file.hpp"

namespace epa::commission {

enum class Stage : int {
  kIdle = 0, kExciting = 1, kIdentifying = 2, kDesigning = 3, kSimulating = 4, kSaving = 5, kVerifying = 6, kDone = 7,
};
enum class Verdict : int { kNone = 0, kDeployed = 1, kRolledBack = 2, kAborted = 3 };

std::string_view to_string(Stage stage);
std::string_view to_string(Verdict verdict);  // "deployed", "rolled-back", "aborted" (epa-commission/1)

// What identification gives the sequence: the model and how well it reproduces the runs.
struct IdentifiedModel {
  core::HammersteinModel model;
  double estimation_fit_pct = 0.0;  // free-run simulation fit on the estimation runs
  double validation_fit_pct = 0.0;  // on the held-out run
  std::vector<double> validation_simulated_mm;  // the model's free run on the held-out run's commands
  std::string summary;              // one line for the log and the report
  std::size_t held_out_run = 0;     // which of the experiment's runs validated it (the others estimated)
  // The stick-slip model fitted beside it (ident/stick_slip_fit.hpp), when the identification fits one,
  // and which of the two describes the axis: the one that follows the held-out run better.
  std::optional<core::StickSlipParams> stick_slip = std::nullopt;
  double stick_slip_validation_fit_pct = 0.0;
  core::AxisModel axis_model = core::AxisModel::kHammerstein;
  // How far the stick-slip model's terms move over parts of the held-out run, and the valve commands
  // the estimation runs covered: what epa identify writes into a model file beside them.
  std::optional<core::StickSlipSpread> stick_slip_spread = std::nullopt;
  std::optional<std::array<double, 2>> identified_drive_v = std::nullopt;  // V: lowest, highest
};
using Identify = std::function<core::Result<IdentifiedModel>(const std::vector<core::Run>& estimation,
                                                             const core::Run& validation)>;

struct Progress {
  Stage stage = Stage::kIdle;
  Verdict verdict = Verdict::kNone;
  double percent = 0.0;  // of the whole sequence, by its expected duration
  std::string message;   // the step under way, or the verdict's reason
};

struct CommissionOutcome {
  Verdict verdict = Verdict::kNone;
  Stage failed_stage = Stage::kIdle;  // where it stopped when not deployed
  std::string reason;
  CommissionSpec spec;
  std::string previous_set, new_set;  // names; new_set empty when none was stored
  std::int64_t previous_set_id = 0, new_set_id = 0;
  std::vector<core::Run> experiment;  // the excitation runs (identified->held_out_run validated the model)
  // Why the first experiment was set aside and run once more (empty: it was not); its runs are not
  // in `experiment`.
  std::string repeated_experiment;
  std::optional<IdentifiedModel> identified;
  std::optional<control::RstDesign> design;
  std::optional<SimulatedVerification> simulation;
  std::vector<JudgedMove> verification;   // on the axis
  std::vector<core::Run> measured_moves;  // their responses
  std::vector<std::string> log;           // every step, with its time
};

class CommissionSequence {
 public:
  using Log = std::function<void(const std::string&)>;
  CommissionSequence(Axis& axis, Identify identify, Log log = {}) : axis_(axis), identify_(std::move(identify)), log_(std::move(log)) {}

  CommissionOutcome run(const CommissionSpec& spec);
  void abort() { abort_ = true; }
  Progress progress() const;

 private:
  // run()'s phases, in order. Each that fails or is aborted finishes the outcome (finish()) and
  // returns false or nothing.
  const CommissionSpec& start(CommissionOutcome& out);  // the spec as run: named, and the progress reset
  bool excite_the_axis(const CommissionSpec& spec, std::uint64_t first_seed, CommissionOutcome& out);
  // The model kept, and why the runs are not one experiment on one axis (empty: they are).
  struct CrossValidated {
    IdentifiedModel kept;
    std::string runs_not_described;
  };
  std::optional<CrossValidated> identify_cross_validated(double loop_period_s, CommissionOutcome& out);
  std::optional<CrossValidated> identify_once_more(const CommissionSpec& spec, double loop_period_s, std::string why,
                                                   CommissionOutcome& out);
  std::optional<store::TuningSet> design_tuning_set(const IdentifiedModel& identified, const store::TuningSet& previous,
                                                    const CommissionSpec& spec, CommissionOutcome& out);
  bool verify_by_simulation(const store::TuningSet& set, const IdentifiedModel& identified, const CommissionSpec& spec,
                            CommissionOutcome& out);
  std::optional<std::int64_t> save_and_run(const store::TuningSet& set, const IdentifiedModel& identified, CommissionOutcome& out);
  bool verify_on_the_axis(const CommissionSpec& spec, CommissionOutcome& out);
  CommissionOutcome& keep(std::int64_t set_id, const std::string& set_name, CommissionOutcome& out);

  double percent_done() const;  // of the whole sequence, by its expected duration
  void step(Stage stage, double percent, const std::string& message, CommissionOutcome& out);
  CommissionOutcome& finish(Verdict verdict, const std::string& reason, CommissionOutcome& out);
  bool aborted(CommissionOutcome& out);

  Axis& axis_;
  Identify identify_;
  Log log_;
  std::atomic<bool> abort_{false};
  mutable std::mutex mutex_;
  Progress progress_;
  bool new_set_running_ = false;
  double total_s_ = 1.0, done_s_ = 0.0;  // the sequence's expected duration (identification weighed as seconds), and what is done
};

// epa-commission/1: the outcome as JSON (verdict, sets, fit figures, design, simulated and measured
// verification moves with rise, settling, e_ss and overshoot).
std::string format_commission_json(const CommissionOutcome& outcome);

}  // namespace epa::commission
