// `epa excite` and `epa identify` as a user runs them: real processes, real files, exit codes and
// messages, and the three-command chain from run files to a simulated step table.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>

#include "core/model_file.hpp"
#include "core/paper_reference.hpp"
#include "core/run_file.hpp"
#include "../support/run_epa.hpp"

namespace {

using epa::testing::run_epa;

constexpr double kBreakPointTolV = 0.02;     // the issue's checks
constexpr double kSlopeRatioRelTol = 0.02;
// Small swarm budgets keep the test fast (the CLI defaults are larger).
const std::string kSmallBudget = " --particles 16 --generations 20";
// The paper's T (eq 11) with its integrating root moved from z = 1 to 0.99: the exact solution for
// eq 11 itself leaves a closed-loop root at z = 1 (docs/paper.md).
const std::string kDesignT = " --T 1,-2.855,2.71575,-0.860706";

class IdentifyCli : public epa::testing::ScratchDirTest {
 protected:
  std::string excite(const std::string& name, int seed, double duration_s, const std::string& extra = "") {
    const auto o = run_epa("excite --out " + path(name) + " --seed " + std::to_string(seed) + " --duration " +
                           std::to_string(duration_s) + extra);
    EXPECT_EQ(o.exit_code, 0) << o.output;
    return path(name);
  }
  void write(const std::string& name, const std::string& text) { std::ofstream(path(name)) << text; }
};

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST_F(IdentifyCli, ExciteWritesAnOpenLoopRunFile) {
  const auto o = run_epa("excite --out " + path("run.csv") + " --duration 20 --seed 3 --plot " + path("run.svg"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("the piston first moved"), std::string::npos) << o.output;
  auto run = epa::core::read_run_file(path("run.csv"), 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->meta("controller"), "open-loop");
  EXPECT_EQ(run->size(), 4000u);
  std::ifstream svg(path("run.svg"));
  std::stringstream s;
  s << svg.rdbuf();
  EXPECT_NE(s.str().find("<svg"), std::string::npos);
}

TEST_F(IdentifyCli, ExciteRunsThePhysicsPlant) {
  write("overlap.toml", "schema = \"epa-pneumatic/1\"\n[valve]\noverlap_pos_v = 1.4\noverlap_neg_v = -1.9\n");
  std::string started[2];
  for (int i = 0; i < 2; ++i) {
    const std::string config = i == 0 ? "" : " --physics-config " + path("overlap.toml");
    const auto o = run_epa("excite --plant physics" + config + " --out " + path("run.csv") + " --duration 20 --seed 3");
    ASSERT_EQ(o.exit_code, 0) << o.output;
    EXPECT_NE(o.output.find("physics plant (" + std::string(i == 0 ? "built-in parameters" : path("overlap.toml")) + ")"),
              std::string::npos)
        << o.output;
    auto run = epa::core::read_run_file(path("run.csv"), 0.005);
    ASSERT_TRUE(run.has_value()) << run.error().message;
    EXPECT_EQ(run->meta("controller"), "open-loop");
    EXPECT_NE(run->meta("source").find("physics plant"), std::string::npos) << run->meta("source");
    EXPECT_EQ(run->size(), 4000u);
    const auto first_moved = o.output.find("the piston first moved");
    ASSERT_NE(first_moved, std::string::npos) << o.output;
    started[i] = o.output.substr(first_moved, 80);
  }
  EXPECT_NE(started[0], started[1]);  // the wider overlap moves the piston later on the ramps
}

TEST_F(IdentifyCli, ExciteRefusesOptionsOfTheOtherPlant) {
  write("plant.toml", "schema = \"epa-pneumatic/1\"\n");
  auto o = run_epa("excite --out " + path("run.csv") + " --physics-config " + path("plant.toml"));
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("--physics-config applies to --plant physics only"), std::string::npos) << o.output;
  o = run_epa("excite --plant physics --out " + path("run.csv") + " --model " + std::string(EPA_SOURCE_DIR) +
              "/config/paper-model.toml");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("--model applies to --plant hammerstein only"), std::string::npos) << o.output;
  write("bad.toml", "schema = \"epa-pneumatic/1\"\n[valve]\noverlap_pos_v = 12\n");
  o = run_epa("excite --plant physics --out " + path("run.csv") + " --physics-config " + path("bad.toml"));
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("overlap_pos_v"), std::string::npos) << o.output;
  o = run_epa("excite --plant pneumatic --out " + path("run.csv"));
  EXPECT_NE(o.exit_code, 0);
}

// Identification on the physics plant from the command line: refined on the simulation error, the
// break points inside the dead band the ramps showed (the acceptance figures: ident_physics_test).
TEST_F(IdentifyCli, IdentifiesThePhysicsPlant) {
  for (int seed : {1, 2}) {
    const auto o = run_epa("excite --plant physics --out " + path("p" + std::to_string(seed) + ".csv") + " --duration 60 --seed " +
                           std::to_string(seed));
    ASSERT_EQ(o.exit_code, 0) << o.output;
  }
  const auto o = run_epa("identify " + path("p1.csv") + " --validate " + path("p2.csv") + " --out " + path("model.toml") +
                         kSmallBudget);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("Dead band read off the slow ramps"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("right break point kept in [+1.3"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("Refinement:"), std::string::npos);
  EXPECT_NE(o.output.find("simulation error V ="), std::string::npos);
  // The model's fits are its row's in the order table: the same model scored from the same first
  // sample (from its own, two samples earlier, it read 68.08 % against the row's 70.20 % once).
  std::smatch row, summary;
  ASSERT_TRUE(std::regex_search(o.output, row, std::regex(R"(\|\s+([0-9.]+)\s+([0-9.]+)\s+\|\s+([0-9.]+)\s+([0-9.]+)\s+\|[^\n]*<- recommended)")))
      << o.output;
  ASSERT_TRUE(std::regex_search(o.output, summary,
                                std::regex(R"(estimation ([0-9.]+) % / ([0-9.]+) %, validation ([0-9.]+) % / ([0-9.]+) %)")))
      << o.output;
  EXPECT_EQ(row[2], summary[1]) << "estimation free-run";
  EXPECT_EQ(row[1], summary[2]) << "estimation one-step";
  EXPECT_EQ(row[4], summary[3]) << "validation free-run";
  EXPECT_EQ(row[3], summary[4]) << "validation one-step";
  auto model = epa::core::read_model_file(path("model.toml"));
  ASSERT_TRUE(model.has_value()) << model.error().message;
  const auto& dz = model->model.dead_zone;
  EXPECT_GT(dz.b_r, 1.2);  // beyond the spool overlap, [-1.7, +1.2] V
  EXPECT_LT(dz.b_r, 1.6);
  EXPECT_LT(dz.b_l, -1.7);
  EXPECT_GT(dz.b_l, -2.1);
  EXPECT_NE(model->source.find("refined on the simulation error"), std::string::npos) << model->source;
  // Break points left to the simulation error alone: near the spool overlap.
  const auto free = run_epa("identify " + path("p1.csv") + " --validate " + path("p2.csv") + " --break-points free --out " +
                            path("free.toml") + kSmallBudget);
  ASSERT_EQ(free.exit_code, 0) << free.output;
  EXPECT_NE(free.output.find("break points free"), std::string::npos);
  EXPECT_EQ(free.output.find("Dead band read off"), std::string::npos);
  auto free_model = epa::core::read_model_file(path("free.toml"));
  ASSERT_TRUE(free_model.has_value()) << free_model.error().message;
  EXPECT_LT(free_model->model.dead_zone.b_r, dz.b_r);
  // The stick-slip model beside it, in the file, and a loop simulated on it.
  EXPECT_NE(o.output.find("Stick-slip model"), std::string::npos) << o.output;
  ASSERT_TRUE(model->stick_slip.has_value());
  EXPECT_GT(model->stick_slip->static_mm, 0.0);
  const auto sim = run_epa("simulate --model " + path("model.toml") + " --plant stick-slip --controller pp-ffidz --start 250 --steps 50 --json " +
                           path("ss.json"));
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  EXPECT_NE(sim.output.find("stick-slip"), std::string::npos) << sim.output;
  std::ifstream json_in(path("ss.json"));
  const auto j = nlohmann::json::parse(json_in);
  EXPECT_EQ(j["plant"], "stick-slip");
  ASSERT_EQ(j["results"].size(), 1u);
  EXPECT_LT(std::abs(j["results"][0]["ess_mm"].get<double>()), 25.0);  // it moved most of the way
  // Without the table there is nothing to simulate on, and the message says where it comes from.
  const auto none = run_epa("simulate --plant stick-slip --controller pp-ffidz --steps 50");
  EXPECT_NE(none.exit_code, 0);
  EXPECT_NE(none.output.find("[stick_slip] table"), std::string::npos) << none.output;
  // The one-step criterion alone cannot see the right side of this plant in runs that keep near
  // the middle, as centring runs do.
  const auto centring = run_epa("excite --plant physics --centring --out " + path("c1.csv") + " --duration 60 --seed 1");
  ASSERT_EQ(centring.exit_code, 0) << centring.output;
  const auto one_step = run_epa("identify " + path("c1.csv") + " --criterion one-step" + kSmallBudget);
  EXPECT_EQ(one_step.exit_code, 1) << one_step.output;
  EXPECT_NE(one_step.output.find("the right"), std::string::npos) << one_step.output;  // named, alone or with the left
  EXPECT_NE(one_step.output.find("of the dead zone"), std::string::npos) << one_step.output;
  EXPECT_NE(one_step.output.find("not identified"), std::string::npos) << one_step.output;
}

TEST_F(IdentifyCli, ExciteRefusesAnAmplitudeBeyondTheValve) {
  const auto o = run_epa("excite --out " + path("run.csv") + " --amplitude-max 12");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("--amplitude-max must lie in (0, 10] V"), std::string::npos) << o.output;
}

// The issue's "done when": run files -> model -> design -> simulated step table, three commands,
// with the same qualitative Table 1 behaviour as the paper's model designed the same way.
TEST_F(IdentifyCli, ThreeCommandsTakeRunFilesToAStepTable) {
  const auto est = excite("est.csv", 1, 60), val = excite("val.csv", 2, 60);
  // An appliance's store to save into (created and seeded by its first start).
  auto o = run_epa("serve --config " + std::string(EPA_SOURCE_DIR) + "/config/epa.toml --modbus-port 0 --web-port 0 " +
                   "--duration 0.2 --db " + path("epa.db") + " --record-dir " + path("runs"));
  ASSERT_EQ(o.exit_code, 0) << o.output;

  o = run_epa("identify " + est + " --validate " + val + " --out " + path("model.toml") + " --plot " + path("fit.svg") +
              " --save rig-1 --db " + path("epa.db") + kSmallBudget);
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("model saved as 'rig-1'"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("Order selection"), std::string::npos);
  EXPECT_NE(o.output.find("<- recommended"), std::string::npos);
  EXPECT_NE(o.output.find("Recommended na="), std::string::npos);
  EXPECT_NE(o.output.find("generation 20/20"), std::string::npos);  // progress
  auto model = epa::core::read_model_file(path("model.toml"));
  ASSERT_TRUE(model.has_value()) << model.error().message;
  const auto& dz = model->model.dead_zone;
  const auto& paper = epa::core::paper::model().dead_zone;
  EXPECT_NEAR(dz.b_r, paper.b_r, kBreakPointTolV);
  EXPECT_NEAR(dz.b_l, paper.b_l, kBreakPointTolV);
  EXPECT_NEAR((dz.m_r / dz.m_l) / (paper.m_r / paper.m_l), 1.0, kSlopeRatioRelTol);
  EXPECT_DOUBLE_EQ(dz.m_l, paper.m_l);  // the normalisation
  EXPECT_NE(model->source.find("epa identify"), std::string::npos);
  std::ifstream svg(path("fit.svg"));
  std::stringstream s;
  s << svg.rdbuf();
  EXPECT_NE(s.str().find("model (free run)"), std::string::npos);
  EXPECT_NE(s.str().find("stick-slip model (free run)"), std::string::npos);

  std::map<std::string, nlohmann::json> table;  // "identified"/"paper" -> epa-sim/1 results
  for (const std::string which : {"identified", "paper"}) {
    const std::string model_option = which == "paper" ? "" : " --model " + path("model.toml");
    o = run_epa("design" + model_option + kDesignT + " --json " + path(which + "-design.json") + " --save designed-on-" + which +
                " --db " + path("epa.db"));
    ASSERT_EQ(o.exit_code, 0) << o.output;
    o = run_epa("simulate" + model_option + " --design " + path(which + "-design.json") + " --json " +
                path(which + "-sim.json"));
    ASSERT_EQ(o.exit_code, 0) << o.output;
    table[which] = read_json(path(which + "-sim.json"))["results"];
  }
  auto result = [&](const std::string& which, const std::string& controller, double step) {
    for (const auto& r : table[which])
      if (r["controller"] == controller && r["step_mm"] == step) return r;
    ADD_FAILURE() << "no result for " << which << " " << controller << " " << step;
    return nlohmann::json{};
  };
  for (double step : {25.0, 50.0, 100.0, 200.0}) {
    for (const std::string which : {"identified", "paper"}) {
      SCOPED_TRACE(which + " model, " + std::to_string(step) + " mm");
      const auto pp = result(which, "pp", step), ng = result(which, "pp-ngidz", step), ff = result(which, "pp-ffidz", step);
      // Table 1's pattern: PP stalls short of the reference; both compensations reach it, FF-IDZ first.
      EXPECT_GT(pp["ess_mm"].get<double>(), 10.0);
      ASSERT_TRUE(ng["rise_s"].is_number() && ff["rise_s"].is_number());
      EXPECT_LT(ff["rise_s"].get<double>(), ng["rise_s"].get<double>());
      EXPECT_LT(ng["ess_mm"].get<double>(), 1.0);
      EXPECT_LT(ff["ess_mm"].get<double>(), 5.0);
    }
    EXPECT_EQ(result("identified", "pp", step)["rise_s"].is_null(), result("paper", "pp", step)["rise_s"].is_null());
  }
  // The store holds the identified model with its fit figures, and a set designed on it.
  o = run_epa("tuning --db " + path("epa.db") + " show designed-on-identified");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("model: rig-1 (id 2)"), std::string::npos) << o.output;  // the saved model, reused
  EXPECT_NE(o.output.find("\"simulation_pct\""), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("model source: epa identify"), std::string::npos) << o.output;
}

// On a cylinder with stiction the model file says the stick-slip model describes the axis, and a set
// designed on it has pp-traj arrive while sliding; on the paper's plant neither.
TEST_F(IdentifyCli, AStickSlipAxisIsRecordedInTheModelFileAndGivesPpTrajItsCoast) {
  auto o = run_epa("serve --config " + std::string(EPA_SOURCE_DIR) + "/config/epa.toml --modbus-port 0 --web-port 0 " +
                   "--duration 0.2 --db " + path("epa.db") + " --record-dir " + path("runs"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  // identify -> model file -> design --save -> tuning show, for one plant: the model file's axis, and
  // what design and show said.
  struct Outcome {
    epa::core::AxisModel axis = epa::core::AxisModel::kHammerstein;
    std::string design, show;
  };
  auto identify_and_save = [&](const std::string& est, const std::string& val, const std::string& name) {
    Outcome out;
    auto r = run_epa("identify " + est + " --validate " + val + " --out " + path(name + ".toml") + kSmallBudget);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    auto model = epa::core::read_model_file(path(name + ".toml"));
    EXPECT_TRUE(model.has_value()) << (model ? "" : model.error().message);
    if (model) out.axis = model->axis_model;
    r = run_epa("design --model " + path(name + ".toml") + kDesignT + " --save on-" + name + " --db " + path("epa.db"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    out.design = r.output;
    r = run_epa("tuning --db " + path("epa.db") + " show on-" + name);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    out.show = r.output;
    return out;
  };

  const auto physics = identify_and_save(excite("phys1.csv", 1, 30, " --plant physics"),
                                         excite("phys2.csv", 2, 30, " --plant physics"), "physics");
  EXPECT_EQ(physics.axis, epa::core::AxisModel::kStickSlip);
  EXPECT_NE(physics.design.find("arrives while sliding"), std::string::npos) << physics.design;
  EXPECT_NE(physics.show.find("pp-traj coast_s: 0.0"), std::string::npos) << physics.show;  // tens of ms
  EXPECT_EQ(physics.show.find("pp-traj coast_s: 0\n"), std::string::npos) << physics.show;

  const auto paper = identify_and_save(excite("paper1.csv", 1, 60), excite("paper2.csv", 2, 60), "paper");
  EXPECT_EQ(paper.axis, epa::core::AxisModel::kHammerstein);
  EXPECT_EQ(paper.design.find("arrives while sliding"), std::string::npos) << paper.design;
  EXPECT_NE(paper.show.find("pp-traj coast_s: 0\n"), std::string::npos) << paper.show;
}

TEST_F(IdentifyCli, TheSameSeedGivesTheSameModelFile) {
  const auto est = excite("est.csv", 4, 30);
  for (const char* name : {"a.toml", "b.toml"}) {
    const auto o = run_epa("identify " + est + " --na 3 --nb 3 --nk 1 --seed 7 --out " + path(name) + kSmallBudget);
    ASSERT_EQ(o.exit_code, 0) << o.output;
    EXPECT_NE(o.output.find("No validation run"), std::string::npos);
  }
  std::ifstream a(path("a.toml")), b(path("b.toml"));
  std::stringstream sa, sb;
  sa << a.rdbuf();
  sb << b.rdbuf();
  EXPECT_EQ(sa.str(), sb.str());
}

// --save into a store that is not there is refused before the fit, and no model file is left
// (an outside walk-through met the refusal after a whole fit, with the model file written).
TEST_F(IdentifyCli, SaveIntoAMissingStoreIsRefusedBeforeTheFit) {
  const auto est = excite("est.csv", 4, 30);
  const auto o = run_epa("identify " + est + " --na 3 --nb 3 --nk 1 --out " + path("m.toml") + " --save rig --db " +
                         path("missing.db") + kSmallBudget);
  EXPECT_EQ(o.exit_code, 1) << o.output;
  EXPECT_NE(o.output.find("--save: no database at " + path("missing.db")), std::string::npos) << o.output;
  EXPECT_EQ(o.output.find("Identified model"), std::string::npos) << "the fit ran first:\n" << o.output;
  EXPECT_FALSE(std::filesystem::exists(path("m.toml")));
}

TEST_F(IdentifyCli, BadRunsGetAnErrorThatSaysWhatToDo) {
  struct Case {
    std::string file, content, expected;
  };
  const std::string header = "# epa-run/1\n# Ts=0.005\n";
  std::string no_u = header + "t_s,y_mm\n", gap = header + "t_s,y_mm,u_V\n", few = header + "t_s,y_mm,u_V\n";
  for (int k = 0; k < 50; ++k) {
    no_u += std::to_string(0.005 * k) + ",250\n";
    gap += std::to_string(0.005 * k + (k > 20 ? 0.005 : 0.0)) + ",250," + (k % 2 ? "2" : "-2") + "\n";
    few += std::to_string(0.005 * k) + "," + std::to_string(250 + k) + "," + (k % 2 ? "2" : "-2") + "\n";
  }
  const Case cases[] = {
      {"no_u.csv", no_u, "missing required column 'u_V'"},
      {"gap.csv", gap, "non-uniform time"},
      {"few.csv", few, "50 usable samples (away from the end stops), identification needs at least 400"},
  };
  for (const auto& c : cases) {
    write(c.file, c.content);
    const auto o = run_epa("identify " + path(c.file));
    EXPECT_EQ(o.exit_code, 1) << c.file;
    EXPECT_NE(o.output.find(c.expected), std::string::npos) << c.file << ": " << o.output;
    EXPECT_NE(o.output.find(path(c.file)), std::string::npos) << "the message names the file";
  }
  // Pulses that never leave the dead band (the paper's is [-1.722, 1.232] V): the piston never moves.
  const auto still = excite("still.csv", 5, 10, " --amplitude-max 1.0");
  auto o = run_epa("identify " + still);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("never leaves the dead band"), std::string::npos) << o.output;
  // Pulses that pass only the right break point: the left side cannot be identified.
  // (Centring: a sweep heading down stays at the top, and then neither side is driven: both named.)
  const auto right_only = excite("right.csv", 6, 30, " --amplitude-max 1.6 --centring");
  o = run_epa("identify " + right_only + kSmallBudget);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("the left side of the dead zone is not identified"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("--amplitude-max"), std::string::npos);
  const auto swept = excite("swept.csv", 6, 30, " --amplitude-max 1.6");
  o = run_epa("identify " + swept + kSmallBudget);
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("left side"), std::string::npos) << o.output;  // "the left side" or "the right and the left sides"
  EXPECT_NE(o.output.find("not identified"), std::string::npos) << o.output;
  // Orders out of range.
  o = run_epa("identify " + still + " --na 4:1");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("--na '4:1': the range is empty"), std::string::npos) << o.output;
  o = run_epa("identify " + still + " --nk 0");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("--nk must be >= 1"), std::string::npos) << o.output;
}

}  // namespace
