// The `epa` command as a user runs it: a real process, real files, exit codes and messages.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "../support/run_epa.hpp"
#include "core/run_file.hpp"

namespace {

using epa::testing::run_epa;
using EpaCli = epa::testing::ScratchDirTest;

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

TEST_F(EpaCli, SimulateWritesTableRunsJsonAndPicture) {
  const auto o = run_epa("simulate --steps 25,50 --out-dir " + path("runs") + " --json " + path("sim.json") +
                         " --plot " + path("resp.svg"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("PP FF-IDZ"), std::string::npos);
  EXPECT_NE(o.output.find("14.72"), std::string::npos);  // the paper's column is printed beside ours

  const auto j = read_json(path("sim.json"));
  EXPECT_EQ(j["schema"], "epa-sim/1");
  EXPECT_EQ(j["Ts"], 0.005);
  ASSERT_EQ(j["results"].size(), 8u);  // four controllers, two steps
  for (const auto& r : j["results"]) {
    if (r["controller"] == "pp" && r["step_mm"] == 25) {
      EXPECT_TRUE(r["rise_s"].is_null());  // never moved
    }
    if (r["controller"] == "pp-ffidz") {
      EXPECT_TRUE(r["rise_s"].is_number());
    }
  }

  auto run = epa::core::read_run_file(path("runs/pp-ffidz_50mm.csv"), 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->meta("controller"), "pp-ffidz");
  EXPECT_EQ(run->size(), 4000u);
  EXPECT_FALSE(run->uc_V.empty());

  std::ifstream svg(path("resp.svg"));
  std::stringstream s;
  s << svg.rdbuf();
  EXPECT_EQ(s.str().rfind("<svg", 0), 0u);
  EXPECT_NE(s.str().find("dead band"), std::string::npos);
}

TEST_F(EpaCli, UnknownControllerIsRefusedWithTheChoices) {
  const auto o = run_epa("simulate --controller pid");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.output.find("unknown controller 'pid'"), std::string::npos) << o.output;
}

// What a new user mistypes: each refused, naming the option and the rule, before anything runs;
// none taken as something else (a wrapped port, a negative seed taken as 2^64 - 3, a negative
// setpoint taken as "not given").
TEST_F(EpaCli, MistypedCommandsAndNumbersAreRefusedNamingWhatWasWrong) {
  const std::string config = "serve --config " + std::string(EPA_SOURCE_DIR) + "/config/epa.toml --db " + path("epa.db") +
                             " --modbus-port 0 --web-port 0 --duration 0.1";
  const struct {
    std::string args, says;
  } cases[] = {
      {"simulat", "'simulat' is not a command; the commands: serve,"},
      {"simulate --lc abc", "--lc: 'abc' is not a number (expected a number >= 0)"},
      {"simulate --noise -1", "--noise: -1 is not a number >= 0"},
      {"simulate --seed -3", "--seed: '-3' is not a seed (expected a whole number >= 0)"},
      {"plant-server --Ts 0", "--Ts: 0 is not a number > 0"},
      {"serve --modbus-port 70000", "--modbus-port: Value 70000 not in range 0 to 65535"},
      {"serve --web-port -1", "--web-port: Value -1 not in range 0 to 65535"},
      {"serve --duration -1", "--duration: -1 is not a number >= 0"},
      {config + " --mode runn", "--mode 'runn' is not a mode; at start-up: stop or run"},
      {config + " --mode manual", "start mode must be stop or run"},
      {config + " --setpoint -5", "start setpoint -5 mm lies outside the setpoint range [0, 500] mm"},
      {config + " --setpoint 700", "start setpoint 700 mm lies outside the setpoint range [0, 500] mm"},
  };
  for (const auto& c : cases) {
    const auto o = run_epa(c.args);
    EXPECT_NE(o.exit_code, 0) << c.args << "\n" << o.output;
    EXPECT_NE(o.output.find(c.says), std::string::npos) << c.args << "\n" << o.output;
    EXPECT_EQ(o.output.find("1797693134862315"), std::string::npos) << c.args << "\n" << o.output;  // DBL_MAX in full
  }
}

// `serve --duration` is how a script runs the appliance for a while: the exit code says whether
// the axis ended the run in FAULT. Plain PP stands still in the dead band 25 mm short (the paper's
// point), so a following error of 10 mm for 0.5 s faults it.
TEST_F(EpaCli, ATimedServeThatEndsInFaultExitsFourAndSaysWhy) {
  std::ifstream shipped(std::string(EPA_SOURCE_DIR) + "/config/epa.toml");
  std::stringstream text;
  text << shipped.rdbuf();
  std::string config = text.str();
  const auto set = [&config](const std::string& line, const std::string& replacement) {
    const auto at = config.find(line);
    ASSERT_NE(at, std::string::npos) << line;
    config.replace(at, line.size(), replacement);
  };
  set("kind = \"pp-traj\"", "kind = \"pp\"");
  set("following_error_mm = 50.0", "following_error_mm = 10.0");
  set("following_error_time_s = 2.0", "following_error_time_s = 0.5");
  set("register_map = \"../registers/epa.csv\"", "register_map = \"" + std::string(EPA_SOURCE_DIR) + "/registers/epa.csv\"");
  set("static_dir = \"../web\"", "static_dir = \"" + std::string(EPA_SOURCE_DIR) + "/web\"");
  std::ofstream(path("epa.toml")) << config;
  const std::string serve = "serve --config " + path("epa.toml") + " --db " + path("epa.db") + " --record-dir " + path("runs") +
                            " --modbus-port 0 --web-port 0 --mode run --duration 1.5 --setpoint ";
  const auto faulted = run_epa(serve + "25");
  EXPECT_EQ(faulted.exit_code, 4) << faulted.output;
  EXPECT_NE(faulted.output.find("the run ended with the axis in FAULT (following-error): exit 4"), std::string::npos)
      << faulted.output;
  const auto held = run_epa(serve + "0");  // nothing to follow: the run ends in RUN
  EXPECT_EQ(held.exit_code, 0) << held.output;
}

TEST_F(EpaCli, BadModelFileIsNamedInTheError) {
  std::ofstream(path("bad.toml")) << "schema = \"epa-model/1\"\nTs = 0.005\n[arx]\nA = [1.0, -0.5]\n";
  const auto o = run_epa("simulate --model " + path("bad.toml"));
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.output.find("bad.toml"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("B"), std::string::npos) << o.output;
}

TEST_F(EpaCli, DesignReproducesEq14And15AndWritesJson) {
  const auto o = run_epa("design --json " + path("design.json"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto j = read_json(path("design.json"));
  EXPECT_EQ(j["schema"], "epa-design/1");
  EXPECT_EQ(j["F"], nlohmann::json({1, -1.778, 0.7828}));
  EXPECT_GT(j["condition_number"].get<double>(), 3.4e3);
  EXPECT_LT(j["condition_number"].get<double>(), 3.8e3);
  ASSERT_EQ(j["closed_loop"].size(), 3u);
  const double eq14[] = {1.0, -3.0551, 3.7470, -2.7583, 1.5027, -0.4362};
  for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(j["closed_loop"][1]["P"][i].get<double>(), eq14[i], 5e-4);
  for (const auto& b : j["closed_loop"]) EXPECT_TRUE(b["jury_stable"].get<bool>()) << b["branch"];
}

TEST_F(EpaCli, ResolvingThePaperEquationReportsIllConditioning) {
  const auto o = run_epa("design --T paper");
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("ILL-CONDITIONED"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("marginal"), std::string::npos) << o.output;  // root at z = 1
}

// A spec whose loop is stable on every branch (the README's example).
TEST_F(EpaCli, DesignFromSpecFeedsSimulate) {
  ASSERT_EQ(run_epa("design --overshoot 0 --settling 0.8 --observer-pole 0.2 --json " + path("d.json")).exit_code, 0);
  const auto o = run_epa("simulate --controller pp-ngidz --steps 50 --design " + path("d.json") + " --json " + path("s.json"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  const auto j = read_json(path("s.json"));
  EXPECT_NEAR(j["results"][0]["ess_mm"].get<double>(), 0.0, 1.0);  // the designed loop reaches 50 mm
}

// A spec that is unstable where the dead zone's slopes apply (5 % in 0.5 s, observer pole 0.5:
// left max |root| 1.07, right 1.32): exit 3, said last, the JSON written for analysis, and --save
// stores nothing.
TEST_F(EpaCli, AnUnstableDesignExitsThreeAndIsNeverSaved) {
  const auto o = run_epa("design --overshoot 5 --settling 0.5 --observer-pole 0.5 --json " + path("d.json"));
  EXPECT_EQ(o.exit_code, 3) << o.output;
  EXPECT_NE(o.output.find("UNSTABLE: the closed loop is unstable on left (max |root| 1.06"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("right (max |root| 1.31"), std::string::npos) << o.output;
  EXPECT_FALSE(read_json(path("d.json"))["closed_loop"][1]["jury_stable"].get<bool>());
  const auto saved = run_epa("design --overshoot 5 --settling 0.5 --observer-pole 0.5 --save fast --db " + path("epa.db"));
  EXPECT_EQ(saved.exit_code, 3) << saved.output;
  EXPECT_NE(saved.output.find("--save: not stored"), std::string::npos) << saved.output;
  const auto listed = run_epa("tuning --db " + path("epa.db") + " list");
  EXPECT_EQ(listed.output.find("fast"), std::string::npos) << listed.output;
}

TEST_F(EpaCli, SpecAndTTogetherAreRefused) {
  const auto o = run_epa("design --T paper --overshoot 2 --settling 2");
  EXPECT_NE(o.exit_code, 0);
  EXPECT_NE(o.output.find("either --T or a spec"), std::string::npos) << o.output;
}

TEST_F(EpaCli, ServeRefusesABadConfigurationNamingFileLineAndKey) {
  std::ofstream(path("bad.toml")) << "[loop]\nperiod_s = 0.005\nperoid_s = 0.001\n";
  const auto o = run_epa("serve --config " + path("bad.toml"));
  EXPECT_EQ(o.exit_code, 1);
  // The wording every TOML reader uses (core/toml_keys.hpp), with the keys [loop] takes.
  EXPECT_NE(o.output.find("bad.toml:3: unknown key 'peroid_s' in [loop] (expected one of: "), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("period_s"), std::string::npos) << o.output;
}

TEST_F(EpaCli, ServeOnTheSimPlantMovesRecordsAndStopsCleanly) {
  // move_window_s 0.5 so that the move is judged (FF-IDZ rings on the paper's plant: a timeout) and
  // recorded within the 1.5 s run.
  std::ofstream(path("fast.toml")) << "[controller]\nkind = \"pp-ffidz\"\n[recorder]\nmove_window_s = 0.5\n[log]\nstatus_interval_s = 0\n"
                                    << "[modbus]\nport = 0\nregister_map = \"" << EPA_SOURCE_DIR << "/registers/epa.csv\"\n"
                                    << "[web]\naddress = \"127.0.0.1\"\nport = 0\nstatic_dir = \"" << EPA_SOURCE_DIR << "/web\"\n";
  const auto o = run_epa("serve --config " + path("fast.toml") + " --mode run --setpoint 100 --duration 1.5 --record-dir " +
                         path("runs") + " --db " + path("epa.db"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("DAQ sim"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("move 1 0.0 -> 100.0 mm"), std::string::npos) << o.output;
  EXPECT_NE(o.output.find("valve 0.000 V"), std::string::npos) << o.output;  // stopped with the valve safe
  auto run = epa::core::read_run_file(path("runs/move-0001-pp-ffidz-0to100mm.csv"), 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message;
  EXPECT_EQ(run->meta("move_end"), "timeout");
  EXPECT_EQ(run->size(), 100u);  // judged 0.5 s after its reference (a step: at once) arrived
}

TEST_F(EpaCli, ServeOnThePhysicsPlantMovesAndRecords) {
  std::ofstream(path("phys.toml")) << "[controller]\nkind = \"pp-ffidz\"\n[recorder]\nmove_window_s = 1.0\n[log]\nstatus_interval_s = 0\n[modbus]\nenabled = false\n"
                                    << "[web]\nenabled = false\n[hal.sim]\nplant = \"physics\"\nphysics_config = \""
                                    << EPA_SOURCE_DIR << "/config/pneumatic-plant.toml\"\n";
  const auto o = run_epa("serve --config " + path("phys.toml") + " --mode run --setpoint 100 --duration 2 --record-dir " +
                         path("runs") + " --db " + path("epa.db"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_NE(o.output.find("DAQ sim (in-process physics plant)"), std::string::npos) << o.output;
  auto run = epa::core::read_run_file(path("runs/move-0001-pp-ffidz-0to100mm.csv"), 0.005);
  ASSERT_TRUE(run.has_value()) << run.error().message << "\n" << o.output;
  EXPECT_NEAR(run->y_mm.back(), 100.0, 5.0);  // within l_c of the target (the physics plant's FF-IDZ finish)
  const auto bad = run_epa("serve --config " + path("phys.toml") + " --db " + path("epa.db") + " --duration 0.1 --hal sim");
  EXPECT_EQ(bad.exit_code, 0) << bad.output;
  std::ofstream(path("bad.toml")) << "[modbus]\nenabled = false\n[web]\nenabled = false\n[hal.sim]\nplant = \"physics\"\n"
                                  << "physics_config = \"" << path("nope.toml") << "\"\n";
  const auto missing = run_epa("serve --config " + path("bad.toml") + " --db " + path("epa.db") + " --duration 0.1");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("[hal.sim]"), std::string::npos) << missing.output;
  EXPECT_NE(missing.output.find("nope.toml"), std::string::npos) << missing.output;
}

TEST_F(EpaCli, PlantServerRunsThePhysicsPlant) {
  const auto o = run_epa("plant-server --plant physics --port 0 --help");
  EXPECT_EQ(o.exit_code, 0);
  EXPECT_NE(o.output.find("--physics-config"), std::string::npos) << o.output;
  const auto bad = run_epa("plant-server --plant cfd --port 0");
  EXPECT_NE(bad.exit_code, 0);
}

TEST_F(EpaCli, ServeRefusesAModbusIoModuleThatIsNotThere) {
  const auto o = run_epa("serve --config " + std::string(EPA_SOURCE_DIR) + "/config/epa.toml --hal modbus-io --modbus-io-port 9 --db " +
                         path("epa.db"));
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("127.0.0.1:9"), std::string::npos) << o.output;
}

}  // namespace
