#pragma once
// The gap over whole moves (from_rest_gap.hpp) of the model the law is designed on (the
// Hammerstein model of the model file) and, when the file holds one, of the axis's stick-slip
// model (plant/stick_slip_model.hpp): how much of the law's model's gap the mechanics it lacks
// explain, and which of them. Friction as mechanics: its stick state follows the piston, which
// sticks when it stands and breaks away once the air spring's wind-up exceeds the breakaway.
//
// A term of the stick-slip model is named when switching it off (the rest as the file has it)
// costs more than its chance threshold of the law's model's gap: friction as static_friction, the
// spool's lag as valve_lag, the dead time as input_delay. Segments are judged only inside the
// valve commands the model file was identified on (identified_drive_v), when it says.
#include <span>
#include <string>
#include <vector>

#include "core/model_file.hpp"
#include "core/run.hpp"
#include "diag/from_rest_gap.hpp"
#include "plant/effects.hpp"

namespace epa::diag {

struct MechanicsTerm {
  plant::EffectKind effect;
  double heldout_without_mm = 0.0;  // the stick-slip model with this term switched off
  double cost_pct = 0.0;            // what that adds, % of the law's model's held-out gap
  bool named = false;
};

struct RunWholeMoveGap {
  std::string set;  // "train" or "heldout"
  std::size_t index = 0;
  double hammerstein_mm = 0.0, stick_slip_mm = 0.0;
  std::size_t segments = 0, segments_left_out = 0;
};

// The first scored run as the report draws it: the readings, both models' free runs from rest (NaN
// where no segment is judged), and where the piston stands, by its readings (1) and in the
// stick-slip model (1: stuck), NaN where not judged.
struct WholeMoveTrace {
  std::string set;
  std::size_t index = 0;
  std::vector<double> t_s, measured_mm, law_model_mm, stick_slip_mm, recorded_rest, model_stuck;
};

struct WholeMoveGap {
  JudgedScope scope;
  bool scoped_to_identified_drive = false;
  double noise_floor_mm = 0.0;
  std::size_t segments = 0, segments_left_out = 0;  // held-out (all runs when cross-validated)
  GapSum hammerstein_train, hammerstein_heldout;
  bool has_stick_slip = false;
  core::StickSlipParams stick_slip;
  GapSum stick_slip_train, stick_slip_heldout;
  double explained_pct = 0.0;  // of the law's model's held-out gap, by the stick-slip model
  std::vector<MechanicsTerm> terms;
  std::vector<plant::EffectKind> named;
  bool unexplained = false;
  std::vector<RunWholeMoveGap> per_run;
  WholeMoveTrace trace;
};

inline constexpr double kMechanicsThresholdPct = 8.0;  // as the effects' chance thresholds
inline constexpr double kSignificantOverFloor = 1.6;   // a gap above this many noise floors is significant

// The scope segments are judged in: the stroke, and the model file's identified drive.
JudgedScope judged_scope(const core::ModelFile& file, double stroke_mm);

// `heldout` empty: the training runs are scored (nothing here is fitted). noise_std_mm: the sensor's.
WholeMoveGap whole_move_gap(const core::ModelFile& file, std::span<const AnchoredRun> train, std::span<const AnchoredRun> heldout,
                            const JudgedScope& scope, double noise_std_mm);

// The friction of the stick-slip model per unit of moving mass, m/s^2 (wind-up x omega^2): times the
// mass in kg, the force in N.
double breakaway_m_s2(const core::StickSlipParams& p);
double sliding_m_s2(const core::StickSlipParams& p);

}  // namespace epa::diag
