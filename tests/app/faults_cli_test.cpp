// `epa faults` as an operator uses it: the binary on a scratch database that `epa serve` made.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>

#include "../support/run_epa.hpp"

namespace {

using epa::testing::run_epa;

class FaultsCli : public epa::testing::ScratchDirTest {
 protected:
  void SetUp() override {
    ScratchDirTest::SetUp();
    std::ofstream(path("epa.toml")) << "[log]\nstatus_interval_s = 0\n[modbus]\nenabled = false\n[web]\nenabled = false\n"
                                    << "[store]\npath = \"" << path("epa.db") << "\"\n[recorder]\ndirectory = \""
                                    << path("runs") << "\"\n";
  }
  epa::testing::Outcome serve() { return run_epa("serve --config " + path("epa.toml") + " --duration 0.3"); }
  epa::testing::Outcome faults(const std::string& args = "") { return run_epa("faults --store " + path("epa.db") + " " + args); }
};

TEST_F(FaultsCli, AFreshStoreHasNoFaults) {
  ASSERT_EQ(serve().exit_code, 0);
  const auto o = faults();
  EXPECT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(o.output, "0 faults since the store was created\n");
  const auto j = faults("--json");
  ASSERT_EQ(j.exit_code, 0) << j.output;
  EXPECT_EQ(nlohmann::json::parse(j.output), nlohmann::json::parse(R"({"count": 0, "faults": []})"));
}

// A damaged database is moved aside and the appliance starts in FAULT: a fault latched before the
// first cycle, with nothing read yet, reaches the history of the new file.
TEST_F(FaultsCli, TheStartFaultOfADamagedDatabaseIsInTheNewOnesHistory) {
  std::ofstream(path("epa.db"), std::ios::binary) << std::string(4096, 'x');
  const auto s = serve();
  ASSERT_EQ(s.exit_code, 4) << s.output;  // the timed run ended in that FAULT (nobody reset it)
  EXPECT_NE(s.output.find("FAULT store-damaged: the tuning database was damaged"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("(in stop, position nan mm"), std::string::npos) << s.output;
  const auto o = faults();
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_TRUE(std::regex_search(o.output, std::regex(R"(^1 fault since the store was created; the newest 1, newest first:\n)"
                                                     R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z  store-damaged +in stop +position - +setpoint 0\.00 mm)")))
      << o.output;
  const auto j = faults("--json --limit 5");
  ASSERT_EQ(j.exit_code, 0) << j.output;
  const auto d = nlohmann::json::parse(j.output);
  EXPECT_EQ(d["count"], 1);
  ASSERT_EQ(d["faults"].size(), 1u);
  EXPECT_EQ(d["faults"][0]["code"], 9);
  EXPECT_EQ(d["faults"][0]["mode"], "stop");
  EXPECT_TRUE(d["faults"][0]["position_mm"].is_null());
  const auto again = serve();  // a second start: the history is read back, nothing added
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(nlohmann::json::parse(faults("--json").output)["count"], 1);
}

TEST_F(FaultsCli, NoDatabaseIsNamedNotCreated) {
  const auto o = faults();
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("no database at " + path("epa.db")), std::string::npos) << o.output;
}

}  // namespace
