#pragma once
// The running comparison of an axis with its commissioned stick-slip model: every move the
// appliance makes is added; over a sliding window of recent moves the model is re-fitted one
// term at a time (axis_change.hpp's vocabulary: friction, flow gain, supply, dead band, spool lag,
// dead time), on the gap over whole moves from rest (from_rest_gap.hpp), and the best change that
// explains the window is named by its effect with its size.
//
// Why a baseline. A model identified on an excitation fits the deployed law's moves less well
// (other speeds, other drives): judged against the commissioned model itself, an unchanged axis
// reads as "friction +37 %" (notes/diagnosis-real-axis.md). So the first baseline_moves after
// deployment are fitted jointly (every continuous term) and that fit, the baseline model, is what
// later windows are compared with; its gap on those moves is the level an unchanged axis keeps.
// A drift is then a change of the baseline model that shrinks a later window's gap by more than
// min_reduction of it, lies beyond the tolerance below, explains the window better than any change
// within it, comes in a window whose gap is wider than every window of the baseline's own, and is
// seen in confirm_windows windows in a row. A window
// whose gap grew beyond unexplained_gap_ratio times the baseline's with no change that explains
// it is unexplained.
//
// Pure: no threads, no clock, so that it can run on a low-priority thread beside the scan cycle
// (appliance/health_monitor.hpp runs it so). bench/health_drift.cpp measures it on the physics
// plant (notes/model-health.md).
#include <array>
#include <cstddef>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "core/run.hpp"
#include "core/stick_slip_params.hpp"
#include "diag/axis_change.hpp"
#include "diag/from_rest_gap.hpp"

namespace epa::diag {

enum class HealthState { kOff, kLearning, kOk, kDrifting, kUnexplained, kHunting };
const char* to_string(HealthState state);  // "off", "learning", "ok", "drifting", "unexplained", "hunting"

struct HealthConfig {
  std::size_t baseline_moves = 24;  // moves the baseline is fitted on (at least window_moves): its 5 windows give the scatter
  std::size_t window_moves = 8;    // moves each later judgement is fitted on
  int confirm_windows = 2;         // judgements in a row that must agree before the state changes
  double min_reduction = 0.25;     // a change must shrink the window's gap by this share of it
  double unexplained_gap_ratio = 2.0;  // a window's gap this many times the baseline's, unexplained: unexplained
  // The smallest changes named, beyond the baseline (axis_change.hpp's floors, each doubled: a
  // window of a few moves scatters more than a diagnosis of whole runs).
  double friction_ratio_tolerance = 0.3;
  double gain_ratio_tolerance = 0.12;
  double break_tolerance_v = 0.12;
  double lag_tolerance_s = 0.008;
  // ... and beyond this many times the widest scatter of the baseline's own windows about it.
  double spread_margin = 1.5;
  std::size_t min_judged_segments = 4;  // a move window with fewer segments from rest is not judged
  double span_s = 1.0;                  // each segment from rest is compared this long (from_rest_gap.hpp): the
                                        // breakaway and the approach, not a cruise whose speed the linear flow extrapolates
  // Returns a message naming the field, or "" when valid.
  std::string problem() const;
};

// The effects the monitor estimates, each by the terms of axis_change.hpp that belong to it.
inline constexpr plant::EffectKind kMonitoredEffects[] = {plant::EffectKind::kStaticFriction, plant::EffectKind::kGainChange,
                                                          plant::EffectKind::kDeadzoneShift, plant::EffectKind::kValveLag,
                                                          plant::EffectKind::kInputDelay};

// One effect's estimate in the latest judgement: the fitted model's term against the baseline
// model's and the commissioned model's. An effect of two terms (the gain: flow or supply) shows
// the one that explains more of the window.
struct EffectEstimate {
  plant::EffectKind effect = plant::EffectKind::kStaticFriction;
  ChangeTerm term = ChangeTerm::kFriction;
  double value = 0.0;         // the term in its unit (friction: breakaway wind-up mm; flow gain: mm/s per V right;
                              // supply: the air spring's frequency rad/s; dead band: the right break point V;
                              // lag: s; dead time: samples)
  double commissioned = 0.0;  // the same term of the commissioned model
  double ratio = 1.0;         // value / commissioned
  double reduction = 0.0;     // of the window's gap against the baseline model, 0..1: how much of it this explains
  bool beyond_tolerance = false;
};

struct HealthVerdict {
  HealthState state = HealthState::kOff;
  std::optional<plant::EffectKind> effect;  // drifting: the effect named
  std::string size;                         // drifting: in words (drift_words: "friction up 80 % since the baseline (...)"); else ""
  double value = 0.0, commissioned = 0.0, ratio = 1.0;  // drifting: the effect's term (EffectEstimate's units)
  std::string unit;                         // of value
  std::size_t moves_seen = 0;               // moves added since the model was set or the baseline retaken
  std::size_t moves_since_onset = 0;        // drifting / unexplained: moves since the first that showed it
  double window_gap_mm = 0.0;               // the latest window's gap against the baseline model
  double baseline_gap_mm = 0.0;             // the baseline model's gap on its own moves
  std::vector<EffectEstimate> estimates;    // the latest judgement, one per effect
  std::string reason;                       // off: why
};

// A drift in words: what the monitor found (the change from the baseline model to the window's, as
// the diagnosis words a change), then where the term stands now and as commissioned. A drift is
// judged against the baseline, which can stand off the commissioned model: told against the
// commissioned model alone, a lag that grew from a baseline below it read "spool faster".
// e.g. "spool slower: lag 10.2 -> 12.8 ms since the baseline (lag 12.8 ms now, lag 13.7 ms as commissioned)".
std::string drift_words(ChangeTerm term, const core::StickSlipParams& baseline, const core::StickSlipParams& now,
                        const core::StickSlipParams& commissioned);

// What one judgement reads from its window, before confirm_windows agree on it.
struct WindowReading {
  HealthState state = HealthState::kOk;            // kOk, kDrifting or kUnexplained
  std::optional<std::size_t> named;                // drifting: the index of the estimate it names
};
// The rules of a judgement, from every term's estimate on the window (one per term, not merged by
// effect): drifting on the estimate beyond its tolerance that explains most, when it explains at
// least min_reduction of the window's gap, at least as much as every estimate within tolerance, and
// the window's gap is wider than unchanged_gap_mm (the widest of the baseline's own windows); else
// unexplained when the gap exceeds unexplained_gap_ratio times baseline_gap_mm; else ok.
WindowReading read_window(const std::vector<EffectEstimate>& per_term, double gap_mm, double unchanged_gap_mm, double baseline_gap_mm,
                          const HealthConfig& config);

class ModelHealth {
 public:
  // drive_range_v: the valve commands the model was identified on (the model file's
  // identified_drive_v); segments that leave it are not judged. Errors: an invalid model or configuration.
  static core::Result<ModelHealth> make(const core::StickSlipParams& commissioned, double Ts, double stroke_mm, HealthConfig config,
                                        std::optional<std::array<double, 2>> drive_range_v = std::nullopt);

  // A move the axis made, at rest at its start (a move's run file); hunted: the law hunted during it.
  // Judges a window when one is due. Returns true when the verdict changed state or effect.
  bool add_move(core::Run run, bool hunted = false);
  // Forgets the baseline: the next baseline_moves are fitted as the new one.
  void retake_baseline();
  const HealthVerdict& verdict() const { return verdict_; }
  const core::StickSlipParams& baseline_model() const { return baseline_; }
  std::size_t fits() const { return fits_; }  // model evaluations so far (cost)

 private:
  ModelHealth(const core::StickSlipParams& commissioned, double Ts, double stroke_mm, HealthConfig config,
              std::optional<std::array<double, 2>> drive_range_v);
  void fit_baseline();
  void judge();
  // The oldest move of the window that `changed` follows more closely than the baseline model.
  std::size_t first_move_explained(const core::StickSlipParams& changed, const core::Run& window) const;

  core::StickSlipParams commissioned_, baseline_;
  double Ts_ = 0.005;
  JudgedScope scope_;
  HealthConfig config_;
  std::deque<core::Run> moves_;  // the newest window (or the baseline's moves while learning)
  bool have_baseline_ = false;
  HealthVerdict verdict_;
  std::optional<plant::EffectKind> candidate_;  // what the last judgements named, and how many in a row
  HealthState candidate_state_ = HealthState::kOk;
  int agreeing_ = 0;
  std::size_t onset_move_ = 0;  // moves_seen at the first judgement of the candidate, less the window
  std::size_t fits_ = 0;
  std::array<double, kChangeTermCount> tolerance_{};  // per term, in the units of its size (model_health.cpp)
  double unchanged_gap_mm_ = 0.0;  // the widest gap of the baseline's own windows against the baseline model
};

}  // namespace epa::diag
