// The commissioning sequence against a simulated axis: deploys a set that passes, rolls back one
// that does not (at once, with the reason, the store's active set never changed), aborts cleanly.
#include "commission/commission_sequence.hpp"

#include <gtest/gtest.h>

#include <map>

#include <nlohmann/json.hpp>

#include "commission/commission_spec.hpp"
#include "commission/move_acceptance.hpp"
#include "core/paper_reference.hpp"
#include "simulated_axis.hpp"

namespace epa::commission {
namespace {

// Identification stand-in: the sequence's logic is under test here, not the fit (tests/ident).
Identify returns(const core::HammersteinModel& model) {
  return [model](const std::vector<core::Run>& estimation, const core::Run&) -> core::Result<IdentifiedModel> {
    if (estimation.empty()) return core::invalid_argument("no runs");
    return IdentifiedModel{model, 99.0, 98.0, {}, "stand-in"};
  };
}

CommissionSpec short_spec() {
  CommissionSpec s;
  s.excitation_runs = 2;
  s.excitation_s = 10.0;
  s.controller = control::ControllerKind::kPpNgidz;
  s.settling_s = 0.5;
  s.overshoot_pct = 0.0;
  s.moves_mm = {150.0, 350.0, 250.0};
  s.move_hold_s = 4.0;
  s.name = "test-set";
  return s;
}

TEST(CommissionSequence, DeploysASetThatPassesEveryCheck) {
  const auto plant = core::paper::model();
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  CommissionSequence seq(axis, returns(plant));
  const auto out = seq.run(short_spec());
  ASSERT_EQ(out.verdict, Verdict::kDeployed) << out.reason;
  EXPECT_EQ(axis.excitations, 2);
  EXPECT_EQ(out.experiment.size(), 2u);
  ASSERT_EQ(out.verification.size(), 3u);
  for (const auto& m : out.verification) EXPECT_TRUE(m.passed) << m.why;
  EXPECT_EQ(axis.loop_set, out.new_set_id);
  EXPECT_EQ(axis.stored_active, out.new_set_id);
  ASSERT_EQ(axis.switches.size(), 2u);  // runs it unpersisted, then keeps it
  EXPECT_FALSE(axis.switches[0].persist);
  EXPECT_TRUE(axis.switches[1].persist);
  EXPECT_LE(axis.max_abs_valve_v, 5.0 + 1e-9);
  const auto j = nlohmann::json::parse(format_commission_json(out));
  EXPECT_EQ(j["schema"], "epa-commission/1");
  EXPECT_EQ(j["verdict"], "deployed");
  EXPECT_EQ(j["new_set"], "test-set");
  EXPECT_EQ(j["previous_set"], "paper");
  EXPECT_EQ(j["verification"].size(), 3u);
  EXPECT_TRUE(j["verification"][0].contains("rise_s"));
  EXPECT_EQ(j["model"]["validation_fit_pct"], 98.0);
  EXPECT_EQ(seq.progress().verdict, Verdict::kDeployed);
  EXPECT_EQ(seq.progress().percent, 100.0);
}

// What identification says of the axis beyond the Hammerstein model reaches the store with it: the
// model record the sequence saves carries the stick-slip model, its spread, the verdict and the
// drive range (the appliance's model-health watch reads them from the deployed set's model).
TEST(CommissionSequence, TheSavedModelCarriesTheIdentifiedStickSlipModelAndItsSpread) {
  const auto plant = core::paper::model();
  core::StickSlipParams stick_slip;
  stick_slip.coulomb_mm = 2.5, stick_slip.static_mm = 3.25, stick_slip.delay_samples = 2;
  const core::StickSlipSpread spread{.friction_log_ratio = 0.3, .flow_gain_log_ratio = 0.08, .break_v = 0.11, .spool_lag_s = 0.012,
                                     .delay_samples = 1.0};
  const std::array<double, 2> drive{-2.75, 3.0};
  Identify identify = [&](const std::vector<core::Run>& estimation, const core::Run& validation) -> core::Result<IdentifiedModel> {
    auto m = returns(plant)(estimation, validation);
    if (!m) return m;
    m->stick_slip = stick_slip;
    m->stick_slip_validation_fit_pct = 99.5;  // follows the held-out run better than the Hammerstein model's 98
    m->stick_slip_spread = spread;
    m->identified_drive_v = drive;
    return m;
  };
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  CommissionSequence seq(axis, identify);
  const auto out = seq.run(short_spec());
  ASSERT_EQ(out.verdict, Verdict::kDeployed) << out.reason;
  ASSERT_TRUE(out.identified);
  EXPECT_EQ(out.identified->axis_model, core::AxisModel::kStickSlip);
  const auto deployed = axis.running();
  ASSERT_TRUE(deployed);
  EXPECT_EQ(deployed->set.id, out.new_set_id);
  const store::ModelRecord& model = deployed->model;
  EXPECT_EQ(model.name, "test-set");
  EXPECT_EQ(model.axis_model, core::AxisModel::kStickSlip);
  EXPECT_EQ(model.stick_slip, stick_slip);
  EXPECT_EQ(model.stick_slip_spread, spread);
  EXPECT_EQ(model.identified_drive_v, drive);
  EXPECT_EQ(model.model.A.coefficients(), plant.A.coefficients());
  EXPECT_NE(model.fit_json.find("\"validation_fit_pct\":98.0"), std::string::npos) << model.fit_json;
  EXPECT_EQ(store::model_file_of(model).stick_slip, stick_slip);
}

// Estimated on the run of `bad_seed`, the stand-in returns a model whose gain is a tenth of the
// plant's (its design cannot pass the simulated moves on the plant's behalf); on any other run,
// the plant. Held-out fits as a real fit would rank them.
Identify bad_when_estimated_on(std::uint64_t bad_seed, std::vector<std::string>& held_out_seeds) {
  return [bad_seed, &held_out_seeds](const std::vector<core::Run>& estimation, const core::Run& validation) -> core::Result<IdentifiedModel> {
    if (estimation.size() != 1) return core::invalid_argument("expected one estimation run");
    held_out_seeds.push_back(validation.meta("excitation_seed"));
    auto plant = core::paper::model();
    if (estimation.front().meta("excitation_seed") != std::to_string(bad_seed))
      return IdentifiedModel{plant, 90.0, 88.0, {}, "from a good run"};
    plant.B = plant.B * 0.1;
    return IdentifiedModel{plant, 60.0, 24.0, {}, "from a bad run"};
  };
}

TEST(CommissionSequence, EachRunIsHeldOutOnceAndTheBestHeldOutFitIsKept) {
  for (const std::uint64_t bad_seed : {1u, 2u}) {  // spec seed 1: runs of seeds 1 and 2
    const auto plant = core::paper::model();
    testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
    std::vector<std::string> held_out;
    CommissionSequence seq(axis, bad_when_estimated_on(bad_seed, held_out));
    const auto out = seq.run(short_spec());
    EXPECT_EQ(held_out, (std::vector<std::string>{"2", "1"})) << "each run held out once";
    ASSERT_EQ(out.verdict, Verdict::kDeployed) << "bad run seed " << bad_seed << ": " << out.reason;
    ASSERT_TRUE(out.identified);
    EXPECT_EQ(out.identified->validation_fit_pct, 88.0);
    EXPECT_EQ(out.experiment[out.identified->held_out_run].meta("excitation_seed"), std::to_string(bad_seed))
        << "the model kept was estimated on the other run";
    EXPECT_EQ(axis.excitations, 2) << "no extra experiment";
  }
}

// Estimated on a run of one of `disturbed_seeds`, the stand-in's model follows that very run at
// 37.5 % (as a run disturbed through its remote I/O gave on the physics rig); on any other, 85 %.
Identify disturbed_when_estimated_on(std::vector<std::uint64_t> disturbed_seeds, std::vector<std::string>& estimated_on) {
  return [disturbed_seeds, &estimated_on](const std::vector<core::Run>& estimation, const core::Run&) -> core::Result<IdentifiedModel> {
    if (estimation.size() != 1) return core::invalid_argument("expected one estimation run");
    const std::string seed = estimation.front().meta("excitation_seed");
    estimated_on.push_back(seed);
    for (const auto bad : disturbed_seeds)
      if (seed == std::to_string(bad)) return IdentifiedModel{core::paper::model(), 37.5, 71.9, {}, "from a disturbed run"};
    return IdentifiedModel{core::paper::model(), 85.0, 86.0, {}, "from a sound run"};
  };
}

TEST(CommissionSequence, AnExperimentItsModelCannotFollowIsRunOnceMoreWithTheNextSeeds) {
  const auto plant = core::paper::model();
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  std::vector<std::string> estimated_on;
  CommissionSequence seq(axis, disturbed_when_estimated_on({1}, estimated_on));
  const auto out = seq.run(short_spec());  // seeds 1 and 2, then 3 and 4
  ASSERT_EQ(out.verdict, Verdict::kDeployed) << out.reason;
  EXPECT_EQ(axis.excitations, 4);
  EXPECT_EQ(estimated_on, (std::vector<std::string>{"1", "2", "3", "4"}));
  ASSERT_EQ(out.experiment.size(), 2u) << "the model is identified on the new runs alone";
  EXPECT_EQ(out.experiment[0].meta("excitation_seed"), "3");
  EXPECT_EQ(out.experiment[1].meta("excitation_seed"), "4");
  ASSERT_TRUE(out.identified);
  EXPECT_EQ(out.identified->estimation_fit_pct, 85.0);
  EXPECT_NE(out.repeated_experiment.find("37.5 %"), std::string::npos) << out.repeated_experiment;
  const auto j = nlohmann::json::parse(format_commission_json(out));
  EXPECT_EQ(j["repeated_experiment"], out.repeated_experiment);
  EXPECT_EQ(seq.progress().percent, 100.0);
}

TEST(CommissionSequence, TheExperimentIsRunOnceMoreAtMostAndASoundOneNotAtAll) {
  const auto plant = core::paper::model();
  {
    testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
    std::vector<std::string> estimated_on;
    CommissionSequence seq(axis, disturbed_when_estimated_on({1, 4}, estimated_on));
    const auto out = seq.run(short_spec());
    EXPECT_EQ(axis.excitations, 4) << "the second experiment is kept whatever it gives";
    ASSERT_TRUE(out.identified);
    EXPECT_EQ(out.identified->estimation_fit_pct, 85.0) << "its better split";
  }
  {
    testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
    std::vector<std::string> estimated_on;
    CommissionSequence seq(axis, disturbed_when_estimated_on({}, estimated_on));
    const auto out = seq.run(short_spec());
    ASSERT_EQ(out.verdict, Verdict::kDeployed) << out.reason;
    EXPECT_EQ(axis.excitations, 2);
    EXPECT_TRUE(out.repeated_experiment.empty());
    EXPECT_TRUE(nlohmann::json::parse(format_commission_json(out))["repeated_experiment"].is_null());
  }
}

TEST(CommissionSequence, ASplitThatCannotBeIdentifiedRunsTheExperimentOnceMore) {
  const auto plant = core::paper::model();
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  Identify identify = [&](const std::vector<core::Run>& estimation, const core::Run& validation) -> core::Result<IdentifiedModel> {
    if (estimation.front().meta("excitation_seed") == "2") return core::invalid_argument("the right break point was not identified");
    return returns(plant)(estimation, validation);
  };
  CommissionSequence seq(axis, identify);
  const auto out = seq.run(short_spec());
  ASSERT_EQ(out.verdict, Verdict::kDeployed) << out.reason;
  EXPECT_EQ(axis.excitations, 4);
  EXPECT_NE(out.repeated_experiment.find("could not be identified"), std::string::npos) << out.repeated_experiment;
}

// Per split (by the held-out run's seed), the Hammerstein and the stick-slip model's held-out fits,
// and whether the split fitted a stick-slip model at all.
struct SplitFits {
  double hammerstein_pct, stick_slip_pct;
  bool has_stick_slip = true;
};
Identify with_fits(std::map<std::string, SplitFits> by_held_out_seed) {
  return [by_held_out_seed](const std::vector<core::Run>&, const core::Run& validation) -> core::Result<IdentifiedModel> {
    const SplitFits& f = by_held_out_seed.at(validation.meta("excitation_seed"));
    IdentifiedModel m{core::paper::model(), 90.0, f.hammerstein_pct, {}, "split held out " + validation.meta("excitation_seed")};
    if (f.has_stick_slip) m.stick_slip = core::StickSlipParams{}, m.stick_slip_validation_fit_pct = f.stick_slip_pct;
    // As one split alone would judge it (report/identify_report.cpp):
    m.axis_model = f.has_stick_slip && f.stick_slip_pct > f.hammerstein_pct ? core::AxisModel::kStickSlip : core::AxisModel::kHammerstein;
    return m;
  };
}

TEST(CommissionSequence, WhichModelDescribesTheAxisIsJudgedOverAllSplits) {
  struct Case {
    const char* what;
    std::map<std::string, SplitFits> fits;  // spec seed 1: runs of seeds 1 and 2
    core::AxisModel expected;
    std::string kept_held_out_seed;
  };
  const std::vector<Case> cases = {
      // Seen on the physics rig through a jittery I/O path: the split the Hammerstein model fits best
      // (by 0.3 points) is the one split where it also beats the stick-slip model.
      {"stick-slip on its best split, Hammerstein on its own", {{"1", {84.1, 83.8}}, {"2", {83.8, 93.7}}},
       core::AxisModel::kStickSlip, "2"},
      // A stick-slip fit that failed on one split (seen there too) does not outvote the other.
      {"a stick-slip fit that failed on one split", {{"1", {92.0, 94.7}}, {"2", {66.5, -20.3}}}, core::AxisModel::kStickSlip, "1"},
      {"Hammerstein on every split", {{"1", {85.0, 80.0}}, {"2", {86.0, 70.0}}}, core::AxisModel::kHammerstein, "2"},
      {"a split without a stick-slip model", {{"1", {80.0, 0.0, false}}, {"2", {79.0, 95.0}}}, core::AxisModel::kHammerstein, "1"},
  };
  for (const auto& c : cases) {
    testing::SimulatedAxis axis(core::paper::model(), testing::paper_running_tuning());
    CommissionSequence seq(axis, with_fits(c.fits));
    const auto out = seq.run(short_spec());
    ASSERT_TRUE(out.identified) << c.what << ": " << out.reason;
    EXPECT_EQ(out.identified->axis_model, c.expected) << c.what;
    EXPECT_EQ(out.experiment[out.identified->held_out_run].meta("excitation_seed"), c.kept_held_out_seed) << c.what;
    if (c.fits.at("1").has_stick_slip && c.fits.at("2").has_stick_slip) {
      EXPECT_NE(out.identified->summary.find(c.expected == core::AxisModel::kStickSlip ? "the stick-slip model describes the axis"
                                                                                        : "the Hammerstein model describes the axis"),
                std::string::npos)
          << c.what << ": " << out.identified->summary;
    }
  }
}

TEST(CommissionSequence, AnIdentificationThatFailsOnEverySplitRollsBackWithTheReason) {
  testing::SimulatedAxis axis(core::paper::model(), testing::paper_running_tuning());
  Identify failing = [](const std::vector<core::Run>&, const core::Run&) -> core::Result<IdentifiedModel> {
    return core::numerical_error("the excitation never left the dead band");
  };
  CommissionSequence seq(axis, failing);
  const auto out = seq.run(short_spec());
  EXPECT_EQ(out.verdict, Verdict::kRolledBack);
  EXPECT_NE(out.reason.find("identification: run 2 held out: the excitation never left the dead band"), std::string::npos) << out.reason;
  EXPECT_EQ(axis.stored_active, 1);
}

TEST(CommissionSequence, AVerificationLimitTheAxisCannotMeetRollsBackAtOnce) {
  // The axis's valve has a dead band 0.6 V wider than the model identification returned: the
  // simulation on the model passes, the axis stops short.
  auto plant = core::paper::model();
  plant.dead_zone.b_r += 0.6, plant.dead_zone.b_l -= 0.6;
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  CommissionSequence seq(axis, returns(core::paper::model()));
  auto spec = short_spec();
  spec.limits.ess_mm = 0.3;
  const auto out = seq.run(spec);
  ASSERT_EQ(out.verdict, Verdict::kRolledBack) << out.reason;
  EXPECT_EQ(out.failed_stage, Stage::kVerifying);
  EXPECT_NE(out.reason.find("on the axis"), std::string::npos) << out.reason;
  ASSERT_TRUE(out.simulation);
  EXPECT_TRUE(out.simulation->passed);
  EXPECT_EQ(axis.loop_set, 1);       // the previous set runs again
  EXPECT_EQ(axis.stored_active, 1);  // and the store never made the new one active
  EXPECT_GE(axis.stops, 1);
  EXPECT_EQ(axis.moves, 1);  // at once: no further move after the first failure
  ASSERT_EQ(axis.switches.size(), 2u);
  EXPECT_EQ(axis.switches[1].id, 1);
  EXPECT_NE(axis.switches[1].reason.find("rolled-back"), std::string::npos);
  EXPECT_LE(axis.max_abs_valve_v, 5.0 + 1e-9);
}

TEST(CommissionSequence, ASpecTheSimulationCannotMeetNeverReachesTheAxis) {
  const auto plant = core::paper::model();
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  CommissionSequence seq(axis, returns(plant));
  auto spec = short_spec();
  spec.limits.settling_s = 0.05;  // no pneumatic axis settles a 100 mm move in 50 ms
  const auto out = seq.run(spec);
  EXPECT_EQ(out.verdict, Verdict::kRolledBack);
  EXPECT_EQ(out.failed_stage, Stage::kSimulating);
  EXPECT_NE(out.reason.find("simulation"), std::string::npos) << out.reason;
  EXPECT_EQ(axis.moves, 0);
  EXPECT_TRUE(axis.switches.empty());
  EXPECT_EQ(axis.stored_active, 1);
}

TEST(CommissionSequence, AbortMidMoveStopsTheValveAndRunsThePreviousSet) {
  const auto plant = core::paper::model();
  testing::SimulatedAxis axis(plant, testing::paper_running_tuning());
  CommissionSequence seq(axis, returns(plant));
  axis.abort_target = &seq;
  axis.abort_after_samples = 300;  // 1.5 s into the first verification move
  const auto out = seq.run(short_spec());
  EXPECT_EQ(out.verdict, Verdict::kAborted);
  EXPECT_EQ(out.failed_stage, Stage::kVerifying);
  EXPECT_EQ(axis.loop_set, 1);
  EXPECT_EQ(axis.stored_active, 1);
  EXPECT_GE(axis.stops, 1);
  EXPECT_EQ(seq.progress().verdict, Verdict::kAborted);
}

TEST(CommissionSequence, AFailedIdentificationLeavesEverythingAsItWas) {
  testing::SimulatedAxis axis(core::paper::model(), testing::paper_running_tuning());
  CommissionSequence seq(axis, [](const std::vector<core::Run>&, const core::Run&) -> core::Result<IdentifiedModel> {
    return core::numerical_error("the right side of the dead zone is not identified");
  });
  const auto out = seq.run(short_spec());
  EXPECT_EQ(out.verdict, Verdict::kRolledBack);
  EXPECT_EQ(out.failed_stage, Stage::kIdentifying);
  EXPECT_NE(out.reason.find("not identified"), std::string::npos);
  EXPECT_TRUE(axis.switches.empty());
  EXPECT_TRUE(out.new_set.empty());
}

// Text that is no JSON says where it breaks; JSON that is no object says what it is (both were
// "not a JSON object", for a truncated spec and for a TOML file alike).
TEST(CommissionSpec, TextThatIsNoSpecSaysWhatItIs) {
  const std::string truncated = parse_commission_spec(R"({"excitation_runs": 2,)").error().message;
  EXPECT_NE(truncated.find("commission spec: not valid JSON: parse error at line 1, column"), std::string::npos) << truncated;
  const std::string toml = parse_commission_spec("excitation_runs = 2\n").error().message;
  EXPECT_NE(toml.find("not valid JSON"), std::string::npos) << toml;
  EXPECT_EQ(parse_commission_spec("[1, 2]").error().message, "commission spec: a JSON object is expected, not array");
}

TEST(CommissionSpec, UnknownKeysAndOutOfRangeValuesAreNamed) {
  EXPECT_NE(parse_commission_spec(R"({"excitation_s": 1})").error().message.find("excitation_s"), std::string::npos);
  EXPECT_NE(parse_commission_spec(R"({"colour": 1})").error().message.find("colour"), std::string::npos);
  EXPECT_NE(parse_commission_spec(R"({"limits": {"ess": 1}})").error().message.find("limits.ess"), std::string::npos);
  EXPECT_NE(parse_commission_spec(R"({"limits": {"ess_mm": "x"}})").error().message.find("limits.ess_mm"), std::string::npos);
  EXPECT_NE(parse_commission_spec(R"({"moves_mm": [100, 900]})").error().message.find("moves_mm"), std::string::npos);
  EXPECT_NE(parse_commission_spec(R"({"controller": "pid"})").error().message.find("controller"), std::string::npos);
  EXPECT_NE(parse_commission_spec(R"({"name": "a b"})").error().message.find("name"), std::string::npos);
  EXPECT_FALSE(parse_commission_spec("[1,2]"));
  auto s = parse_commission_spec(R"({"excitation_runs": 3, "moves_mm": [100, 200], "limits": {"ess_mm": 0.5}, "name": "x-1"})");
  ASSERT_TRUE(s) << s.error().message;
  auto back = parse_commission_spec(format_commission_spec(*s));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->excitation_runs, 3);
  EXPECT_EQ(back->moves_mm, (std::vector<double>{100, 200}));
  EXPECT_EQ(back->limits.ess_mm, 0.5);
  EXPECT_EQ(back->name, "x-1");
  auto mm = parse_commission_spec(R"({"limits": {"overshoot_mm": 12}, "robust_limits": {"overshoot_mm": 20}})");
  ASSERT_TRUE(mm) << mm.error().message;
  auto mm_back = parse_commission_spec(format_commission_spec(*mm));
  ASSERT_TRUE(mm_back);
  EXPECT_EQ(mm_back->limits.overshoot_mm, 12.0);
  EXPECT_EQ(mm_back->robust_limits.overshoot_mm, 20.0);
  EXPECT_NE(parse_commission_spec(R"({"limits": {"overshoot_mm": -1}})").error().message.find("limits.overshoot_mm"), std::string::npos);
}

// An overshoot passes when it is within the percentage or, if given, within overshoot_mm: one
// breakaway jump of ~12 mm is 24 % of a 50 mm move and 6 % of a 200 mm one.
TEST(MoveAcceptance, AnOvershootPassesWithinItsPercentageOrWithinItsMillimetres) {
  core::StepMetrics m;
  m.moved = true;
  m.settling_s = 0.5;
  m.ess_mm = 1.0;
  m.overshoot_pct = 24.0;  // 12 mm of a 50 mm move
  MoveLimits pct_only{.ess_mm = 8.0, .overshoot_pct = 20.0, .overshoot_mm = 0.0, .settling_s = 0.0};
  const auto refused = judge_move(250.0, 200.0, m, pct_only);
  EXPECT_FALSE(refused.passed);
  EXPECT_NE(refused.why.find("overshoot 24.0 % (12.00 mm), limit 20.0 %"), std::string::npos) << refused.why;
  MoveLimits with_mm = pct_only;
  with_mm.overshoot_mm = 15.0;
  EXPECT_TRUE(judge_move(250.0, 200.0, m, with_mm).passed);
  with_mm.overshoot_mm = 11.0;
  const auto beyond = judge_move(250.0, 200.0, m, with_mm);
  EXPECT_FALSE(beyond.passed);
  EXPECT_NE(beyond.why.find("limit 20.0 % or 11 mm"), std::string::npos) << beyond.why;
  m.overshoot_pct = 6.0;  // 12 mm of a 200 mm move: within the percentage
  EXPECT_TRUE(judge_move(50.0, 250.0, m, pct_only).passed);
}

}  // namespace
}  // namespace epa::commission
