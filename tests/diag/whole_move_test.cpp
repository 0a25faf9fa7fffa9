// The gap over whole moves: where a run rests, the free run from there, its noise floor against
// the windowed gap's, the drive range it is judged in, the mechanics a stick-slip model adds to the
// law's model, and what changed since commissioning.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/format.hpp"
#include "core/paper_reference.hpp"
#include "core/random.hpp"
#include "diag/axis_change_selection.hpp"
#include "diag/from_rest_gap.hpp"
#include "diag/rest_anchors.hpp"
#include "diag/selection.hpp"
#include "diag/stick_slip_spread.hpp"
#include "diag/whole_move.hpp"
#include "plant/hammerstein_plant.hpp"
#include "plant/pneumatic_plant.hpp"
#include "plant/stick_slip_model.hpp"

namespace epa::diag {
namespace {

constexpr double kTs = 0.005;
constexpr double kNoiseMm = 0.1;

// Pulses of `level` V each way from rest, each held `pulse_s` then `rest_s` at 0 V: what
// epa excite and a sequence of moves look like to the diagnosis.
std::vector<double> pulse_train(double level, double pulse_s, double rest_s, int pulses, std::uint64_t seed) {
  core::Random rng(seed);
  std::vector<double> u;
  for (int i = 0; i < pulses; ++i) {
    const double v = (i % 2 ? -1.0 : 1.0) * level * (0.8 + 0.4 * rng.uniform());
    u.insert(u.end(), static_cast<std::size_t>(std::lround(rest_s / kTs)), 0.0);
    u.insert(u.end(), static_cast<std::size_t>(std::lround(pulse_s * (0.7 + 0.6 * rng.uniform()) / kTs)), v);
  }
  u.insert(u.end(), static_cast<std::size_t>(std::lround(rest_s / kTs)), 0.0);
  return u;
}

// A run of any plant with step(u) and a true position, read with seeded noise.
template <class Step>
core::Run record(const std::vector<double>& u, std::uint64_t seed, Step&& step_to_position_mm, double y0_mm) {
  core::Random rng(seed);
  core::Run run;
  run.Ts = kTs;
  double y = y0_mm;
  for (std::size_t k = 0; k < u.size(); ++k) {
    run.t_s.push_back(static_cast<double>(k) * kTs);
    run.y_mm.push_back(y + kNoiseMm * rng.normal());
    run.u_V.push_back(u[k]);
    y = step_to_position_mm(u[k]);
  }
  return run;
}

core::Run stick_slip_run(const core::StickSlipParams& p, std::uint64_t seed, double level = 2.6) {
  auto model = *plant::StickSlipModel::make(p, kTs);
  model.reset(250.0);
  return record(pulse_train(level, 0.25, 0.6, 24, seed), seed, [&](double u) { return model.step(u); }, 250.0);
}

core::StickSlipParams commissioned() {
  core::StickSlipParams p;
  p.break_right_v = 1.15, p.break_left_v = -1.62, p.speed_right_mm_s_per_v = 104.0, p.speed_left_mm_s_per_v = 92.0;
  p.spring_rad_s = 50.0, p.damping_ratio = 0.3, p.coulomb_mm = 5.0, p.static_mm = 8.6, p.spool_lag_s = 0.013, p.delay_samples = 0;
  return p;
}

std::vector<const core::Run*> pointers(const std::vector<core::Run>& runs) {
  std::vector<const core::Run*> p;
  for (const auto& r : runs) p.push_back(&r);
  return p;
}

// ---- where the state is known ---------------------------------------------------------------

// On the physics plant (another structure than any model here): every anchor lies where the true
// piston stands, and its position is the rest's mean to within the noise of that mean.
TEST(RestAnchors, AnchorsLieWhereThePhysicsPistonStandsAtItsMeanPosition) {
  auto plant = *plant::PneumaticPlant::make({}, {.initial_position_mm = 250.0});
  const auto u = pulse_train(2.8, 0.25, 0.6, 12, 7);
  std::vector<double> truth;
  const core::Run run = record(u, 7, [&](double v) { return plant.step(v), truth.push_back(plant.position_mm()), plant.position_mm(); }, 250.0);
  truth.insert(truth.begin(), 250.0);
  const RestAnchors rests = rest_anchors(run);
  EXPECT_NEAR(rests.noise_std_mm, kNoiseMm, 0.02);
  ASSERT_GE(rests.anchors.size(), 12u);  // the start and (nearly) every rest between the pulses
  for (const auto& a : rests.anchors) {
    for (std::size_t i = 0; i < a.readings; ++i)
      ASSERT_NEAR(truth[a.k - i], truth[a.k], 0.05) << "the piston moved inside the rest anchored at " << a.k;
    EXPECT_NEAR(a.position_mm, truth[a.k], 4.0 * kNoiseMm / std::sqrt(static_cast<double>(a.readings))) << a.k;
  }
}

// ---- a floor set by the sensor alone ----------------------------------------------------------

// The paper's model is integrating: restarted from noisy readings every 10 samples it turns 0.1 mm
// of sensor noise into a floor twice that (an identified model of a physics axis: six times). Restarted only where the piston rests, from the
// mean of the readings there, the model's own gap on its own noisy runs is the sensor's noise.
TEST(FromRestGap, TheTrueModelsGapIsTheSensorNoiseNotItsOwnAmplification) {
  const auto model = core::paper::model();
  auto plant = *plant::HammersteinPlant::make(model, {.initial_position_mm = 250.0});
  const core::Run run = record(pulse_train(2.4, 0.15, 0.6, 30, 3), 3, [&](double u) { return plant.step(u), plant.position_mm(); }, 250.0);
  const std::vector<AnchoredRun> runs{{&run, rest_anchors(run)}};
  const double gap = from_rest_gap_mm(model, runs, JudgedScope{});
  const double floor = from_rest_noise_floor_mm(runs, kNoiseMm);
  EXPECT_NEAR(gap, floor, 0.15 * floor);
  EXPECT_LT(floor, 1.1 * kNoiseMm);
  EXPECT_GT(noise_floor_mm(model, kNoiseMm, 10), 1.8 * floor);  // the windowed gap's floor on the same model
}

// A segment driven outside the identified range is left out and counted; so is one at an end stop.
TEST(FromRestGap, SegmentsOutsideTheIdentifiedDriveOrAtAnEndStopAreLeftOutAndCounted) {
  const core::Run run = stick_slip_run(commissioned(), 5, 2.6);
  const std::vector<AnchoredRun> runs{{&run, rest_anchors(run)}};
  const GapSum all = from_rest_sse(commissioned(), kTs, runs[0], JudgedScope{});
  JudgedScope narrow;
  narrow.drive_lo_v = -1.0, narrow.drive_hi_v = 1.0;
  const GapSum inside = from_rest_sse(commissioned(), kTs, runs[0], narrow);
  EXPECT_GT(all.windows, 10u);
  EXPECT_LE(inside.windows, 1u) << "every segment but the last rest holds a pulse beyond 1 V";
  EXPECT_EQ(inside.windows + inside.windows_at_end_stop, all.windows + all.windows_at_end_stop);
  JudgedScope short_stroke;
  short_stroke.stroke_mm = 200.0;  // the run works around 250 mm: beyond this stroke's end
  EXPECT_EQ(from_rest_sse(commissioned(), kTs, runs[0], short_stroke).windows, 0u);
}

// ---- mechanics the law's model lacks ---------------------------------------------------------

// A Hammerstein model epa identify fitted on the physics plant (the law's model of its axis).
core::HammersteinModel identified_on_physics() {
  core::HammersteinModel m = core::paper::model();
  m.A = core::Polynomial({1.0, -1.9048374134693686, 0.9048374134693686});
  m.B = core::Polynomial({0.0, 0.0, 0.0009552740192351853});
  m.dead_zone = {.m_r = 1.2097, .m_l = 1.0707, .b_r = 1.345, .b_l = -1.8175};
  return m;
}

// On runs of an axis that sticks (the stick-slip model itself: the physics plant is judged by the
// rig test, tests/diag/physics_rig_test.sh), the model file's stick-slip model explains most of the
// law's model's gap over whole moves, and friction is named: switching it off costs more than its
// threshold. A gain the law's model has wrong is no mechanics: the stick-slip model follows such
// an axis better, but none of its terms is named for that. Without a stick-slip table
// nothing is named and the gap is the law's model's alone.
TEST(WholeMove, TheStickSlipMechanicsExplainTheLawModelsGapAndNameFrictionOnlyWhenTheyDo) {
  core::ModelFile file{identified_on_physics(), "identified"};
  file.stick_slip = commissioned();
  const std::vector<core::Run> train{stick_slip_run(commissioned(), 11), stick_slip_run(commissioned(), 12)},
      held{stick_slip_run(commissioned(), 13)};
  const auto tr = anchor_runs(pointers(train)), ho = anchor_runs(pointers(held));
  const WholeMoveGap g = whole_move_gap(file, tr, ho, judged_scope(file, 500.0), kNoiseMm);
  ASSERT_TRUE(g.has_stick_slip);
  EXPECT_GT(g.hammerstein_heldout.rms_mm(), 3.0 * g.stick_slip_heldout.rms_mm());
  EXPECT_GT(g.explained_pct, 60.0);
  ASSERT_FALSE(g.named.empty());
  EXPECT_EQ(g.named.front(), plant::EffectKind::kStaticFriction);
  EXPECT_EQ(g.per_run.size(), 3u);

  // An axis that barely sticks, against the paper's model whose gain is far off: the stick-slip
  // model follows it better, by its speeds; its friction and lag are not named for that.
  core::StickSlipParams slippery = commissioned();
  slippery.coulomb_mm = 0.05, slippery.static_mm = 0.06, slippery.spool_lag_s = 0.001;
  core::ModelFile paper{core::paper::model(), "paper"};
  paper.stick_slip = slippery;
  const std::vector<core::Run> slippery_train{stick_slip_run(slippery, 14)}, slippery_held{stick_slip_run(slippery, 15)};
  const WholeMoveGap against_paper = whole_move_gap(paper, anchor_runs(pointers(slippery_train)), anchor_runs(pointers(slippery_held)),
                                                    judged_scope(paper, 500.0), kNoiseMm);
  EXPECT_GT(against_paper.explained_pct, 60.0);
  EXPECT_TRUE(against_paper.named.empty()) << "a gain the paper's model has wrong is no friction";

  file.stick_slip.reset();
  const WholeMoveGap plain = whole_move_gap(file, tr, ho, judged_scope(file, 500.0), kNoiseMm);
  EXPECT_FALSE(plain.has_stick_slip);
  EXPECT_TRUE(plain.named.empty());
  EXPECT_TRUE(plain.unexplained);  // the Hammerstein model alone misses a sticking axis by far more than noise
}

// ---- what changed since commissioning --------------------------------------------------------

TEST(AxisChange, ApplyingAChangeScalesOrShiftsOnlyItsTerms) {
  const auto c = commissioned();
  AxisChange change;
  change.terms = {ChangeTerm::kFriction, ChangeTerm::kDeadBand, ChangeTerm::kDeadTime};
  change.values = {{2.0}, {0.1, -0.2}, {}};
  change.delay_samples = 3;
  const auto p = apply_change(c, change);
  EXPECT_DOUBLE_EQ(p.coulomb_mm, 2.0 * c.coulomb_mm);
  EXPECT_DOUBLE_EQ(p.static_mm, 2.0 * c.static_mm);
  EXPECT_DOUBLE_EQ(p.break_right_v, c.break_right_v + 0.1);
  EXPECT_DOUBLE_EQ(p.break_left_v, c.break_left_v - 0.2);
  EXPECT_EQ(p.delay_samples, 3);
  EXPECT_EQ(p.speed_right_mm_s_per_v, c.speed_right_mm_s_per_v);
  EXPECT_EQ(describe_change(ChangeTerm::kFriction, change, c), "friction up 100 %");
  EXPECT_EQ(describe_change(ChangeTerm::kDeadTime, change, c), "line longer: dead time 0 -> 3 samples");
  // Within the spread (twice it) a change is not beyond tolerance; beyond, it is.
  core::StickSlipSpread spread;
  spread.friction_log_ratio = 0.4;
  EXPECT_FALSE(beyond_tolerance(ChangeTerm::kFriction, change, c, spread));  // ln 2 = 0.69 < 0.8
  spread.friction_log_ratio = 0.3;
  EXPECT_TRUE(beyond_tolerance(ChangeTerm::kFriction, change, c, spread));
}

// A lower supply as the model holds it: a softer air spring that the friction winds further, the
// speeds kept; named as the gain effect, told in the spring's frequency, and held to friction's
// tolerance.
TEST(AxisChange, TheSupplySoftensTheSpringAndWindsItFurther) {
  const auto c = commissioned();
  AxisChange change;
  change.terms = {ChangeTerm::kSupply};
  change.values = {{0.5}};
  const auto p = apply_change(c, change);
  EXPECT_DOUBLE_EQ(p.spring_rad_s, 0.5 * c.spring_rad_s);
  EXPECT_DOUBLE_EQ(p.static_mm, 2.0 * c.static_mm);
  EXPECT_DOUBLE_EQ(p.coulomb_mm, 2.0 * c.coulomb_mm);
  EXPECT_EQ(p.speed_right_mm_s_per_v, c.speed_right_mm_s_per_v);
  EXPECT_EQ(effect_of(ChangeTerm::kSupply), plant::EffectKind::kGainChange);
  EXPECT_NEAR((*change_between(ChangeTerm::kSupply, c, p).values_of(ChangeTerm::kSupply))[0], 0.5, 1e-12);
  EXPECT_EQ(describe_change(ChangeTerm::kSupply, change, c),
            "air spring softer: " + core::format_number(std::round(c.spring_rad_s)) + " -> " +
                core::format_number(std::round(0.5 * c.spring_rad_s)) + " rad/s (supply pressure down)");
  core::StickSlipSpread spread;
  spread.flow_gain_log_ratio = 2.0;  // the flow gain's spread does not hold it
  spread.friction_log_ratio = 0.3;   // ln 2 = 0.69 > 0.6
  EXPECT_TRUE(beyond_tolerance(ChangeTerm::kSupply, change, c, spread));
  spread.friction_log_ratio = 0.4;
  EXPECT_FALSE(beyond_tolerance(ChangeTerm::kSupply, change, c, spread));
}

// Runs of the commissioned model itself name no change; the same with its friction doubled name
// static_friction with about that ratio; without the model's spread nothing is judged.
TEST(AxisChange, AFrictionChangeOfTheModelIsNamedAndNoneWhereThereIsNone) {
  const auto c = commissioned();
  core::StickSlipParams doubled = c;
  doubled.coulomb_mm *= 2.0, doubled.static_mm *= 2.0;
  core::StickSlipSpread spread;
  spread.friction_log_ratio = 0.05, spread.flow_gain_log_ratio = 0.02, spread.break_v = 0.02, spread.spool_lag_s = 0.002;
  for (const bool changed : {false, true}) {
    const auto truth = changed ? doubled : c;
    const std::vector<core::Run> train{stick_slip_run(truth, 21), stick_slip_run(truth, 22)}, held{stick_slip_run(truth, 23)};
    const auto tr = anchor_runs(pointers(train)), ho = anchor_runs(pointers(held));
    const ChangeFitData data{c, kTs, tr, ho, JudgedScope{}};
    const AxisChanges found = select_axis_changes(data, spread, 0.1, false);
    EXPECT_TRUE(found.judged);
    if (!changed) {
      EXPECT_TRUE(found.accepted.terms.empty());
      continue;
    }
    ASSERT_FALSE(found.accepted.terms.empty());
    EXPECT_EQ(found.accepted.terms.front(), ChangeTerm::kFriction);
    EXPECT_NEAR((*found.accepted.values_of(ChangeTerm::kFriction))[0], 2.0, 0.3);
    EXPECT_GT(found.reduction_pct, 50.0);
    EXPECT_FALSE(select_axis_changes(data, std::nullopt, 0.1, false).judged);
    EXPECT_TRUE(select_axis_changes(data, std::nullopt, 0.1, false).accepted.terms.empty());
  }
}

// The spread of the model over parts of runs it describes exactly is small.
TEST(StickSlipSpread, OnRunsOfTheModelItselfTheSpreadIsSmall) {
  const auto c = commissioned();
  const std::vector<core::Run> runs{stick_slip_run(c, 31)};
  const auto spread = stick_slip_spread(c, kTs, pointers(runs), JudgedScope{});
  EXPECT_LT(spread.friction_log_ratio, 0.1);
  EXPECT_LT(spread.flow_gain_log_ratio, 0.05);
  EXPECT_LT(spread.break_v, 0.05);
  EXPECT_EQ(spread.delay_samples, 0.0);
}

}  // namespace
}  // namespace epa::diag
