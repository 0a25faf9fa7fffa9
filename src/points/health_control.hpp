#pragma once
// The model-health monitor as the interfaces see it (appliance/health_monitor.* implements it):
// Modbus reads its verdict as points and retakes its baseline through the write gate's
// health_command point; the status page and the JSON API show the verdict with its words.
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace epa::points {

// Numeric values are the Modbus interface (health_state, health_effect): append only.
enum class HealthStateCode : std::uint8_t { kOff, kLearning, kOk, kDrifting, kUnexplained, kHunting };
inline constexpr std::array<std::string_view, 6> kHealthStateNames = {"off", "learning", "ok", "drifting", "unexplained", "hunting"};
// The effects the diagnosis names (plant/effects.hpp's names), 0: none.
enum class HealthEffectCode : std::uint8_t { kNone, kStaticFriction, kGainChange, kDeadzoneShift, kValveLag, kInputDelay };
inline constexpr std::array<std::string_view, 6> kHealthEffectNames = {"", "static_friction", "gain_change", "deadzone_shift",
                                                                       "valve_lag", "input_delay"};

inline std::string_view to_string(HealthStateCode s) { return kHealthStateNames[static_cast<std::size_t>(s)]; }
inline std::string_view to_string(HealthEffectCode e) { return kHealthEffectNames[static_cast<std::size_t>(e)]; }

// A warning (status bit 6 and health_warning): the axis has drifted from its model, or hunts.
inline bool health_warns(HealthStateCode s) {
  return s == HealthStateCode::kDrifting || s == HealthStateCode::kUnexplained || s == HealthStateCode::kHunting;
}

// What a Modbus request reads: numbers only, copied per request.
struct HealthView {
  HealthStateCode state = HealthStateCode::kOff;
  HealthEffectCode effect = HealthEffectCode::kNone;
  double value = std::numeric_limits<double>::quiet_NaN();         // the effect's term now (unit: HealthReport::unit)
  double commissioned = std::numeric_limits<double>::quiet_NaN();  // the same term of the commissioned model
  double ratio = std::numeric_limits<double>::quiet_NaN();         // value / commissioned
  std::uint32_t moves_seen = 0;         // moves judged since the model was set or the baseline retaken
  std::uint32_t moves_since_onset = 0;  // drifting / unexplained: moves since the first that showed it
};

// One effect's estimate in the latest judgement, for the page's trend.
struct HealthEstimate {
  HealthEffectCode effect = HealthEffectCode::kNone;
  double ratio = 1.0;      // to the commissioned term
  double reduction = 0.0;  // share of the window's gap it explains, 0..1
};

// One judgement: the move it was made at and each effect's estimate.
struct HealthJudgement {
  std::uint32_t move = 0;  // moves_seen when it was made
  std::vector<HealthEstimate> estimates;
};

// The verdict in words, for JSON.
struct HealthReport {
  HealthView view;
  std::string size;    // drifting: in words (diag::drift_words: "friction up 80 % since the baseline (...)"); else ""
  std::string unit;    // of value and commissioned
  std::string reason;  // off: why; else what the state means now
  double window_gap_mm = std::numeric_limits<double>::quiet_NaN();    // the latest window against the baseline model
  double baseline_gap_mm = std::numeric_limits<double>::quiet_NaN();  // the baseline model on its own moves
  std::uint64_t moves_dropped = 0;  // moves that arrived while the monitor was still busy (not judged)
  std::vector<HealthJudgement> trend;  // the newest judgements, oldest first
};

class HealthControl {
 public:
  virtual ~HealthControl() = default;
  virtual HealthView view() const = 0;
  // With `with_trend` false, `trend` is left empty (what /api/status needs, polled 4 times a second).
  virtual HealthReport report(bool with_trend) const = 0;
  // Forgets the baseline: the next moves are learnt as the new one. `source`: who asked (audit).
  virtual void retake_baseline(const std::string& source) = 0;
};

}  // namespace epa::points
