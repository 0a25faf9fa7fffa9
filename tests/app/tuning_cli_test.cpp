// `epa tuning` and `epa serve` with the tuning store, as an operator uses them: the binary on a
// scratch database.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "../support/run_epa.hpp"
#include "store/database.hpp"
#include "store/statement.hpp"

namespace {

using epa::testing::run_epa;

class TuningCli : public epa::testing::ScratchDirTest {
 protected:
  void SetUp() override {
    ScratchDirTest::SetUp();
    std::ofstream(path("epa.toml")) << "[log]\nstatus_interval_s = 0\n[modbus]\nport = 0\nregister_map = \"" << EPA_SOURCE_DIR
                                    << "/registers/epa.csv\"\n[web]\nenabled = false\n[store]\npath = \"" << path("epa.db")
                                    << "\"\n[recorder]\ndirectory = \"" << path("runs") << "\"\n";
  }
  epa::testing::Outcome serve(const std::string& extra = "") {
    return run_epa("serve --config " + path("epa.toml") + " --duration 0.3 " + extra);
  }
  epa::testing::Outcome tuning(const std::string& args) { return run_epa("tuning --db " + path("epa.db") + " " + args); }
  std::string read(const std::string& name) {
    std::ifstream in(path(name));
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  void sql(const std::string& statement) {
    auto db = epa::store::Database::open(path("epa.db"), false);
    ASSERT_TRUE(db) << db.error().message;
    ASSERT_TRUE(db->exec(statement));
  }
};

TEST_F(TuningCli, TheFirstStartSeedsThePaperSetAndMarksItActive) {
  const auto s = serve();
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("created " + path("epa.db")), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("tuning set 'paper'"), std::string::npos) << s.output;
  const auto list = tuning("list");
  ASSERT_EQ(list.exit_code, 0) << list.output;
  EXPECT_TRUE(std::regex_search(list.output, std::regex(R"(\*\s+1\s+paper\s+pp-traj)"))) << list.output;
  const auto show = tuning("show paper");
  EXPECT_NE(show.output.find("F: [1, -1.778, 0.7828]"), std::string::npos) << show.output;
  EXPECT_NE(show.output.find("(active)"), std::string::npos) << show.output;
  const auto again = serve();
  EXPECT_EQ(again.output.find("created"), std::string::npos) << again.output;  // reopened, not re-created
}

TEST_F(TuningCli, ExportImportDiffAndActivateAreAudited) {
  ASSERT_EQ(serve().exit_code, 0);
  ASSERT_EQ(tuning("export paper --out " + path("paper.toml")).exit_code, 0);
  const auto same = tuning("import " + path("paper.toml") + " --name copy");
  ASSERT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(tuning("diff paper copy").output.find("have the same values"), std::string::npos);

  std::string text = read("paper.toml");
  text.replace(text.find("lc_mm = 5.0"), 11, "lc_mm = 7.5");
  std::ofstream(path("wider.toml")) << text;
  ASSERT_EQ(tuning("import " + path("wider.toml") + " --name wider --activate").exit_code, 0);
  const auto diff = tuning("diff paper wider");
  EXPECT_NE(diff.output.find("lc_mm:\n  paper: 5\n  wider: 7.5"), std::string::npos) << diff.output;
  EXPECT_EQ(tuning("list").output.find("* "), tuning("list").output.find("*   3  wider")) << tuning("list").output;
  EXPECT_EQ(tuning("show wider").output.find("model: paper (id 1)") != std::string::npos, true)
      << "the identical model is reused, not copied:\n" << tuning("show wider").output;

  const auto audit = tuning("audit --point active_tuning_set");
  EXPECT_NE(audit.output.find("cli  active_tuning_set  1 -> 3"), std::string::npos) << audit.output;
  const auto s = serve();
  EXPECT_NE(s.output.find("tuning set 'wider'"), std::string::npos) << s.output;

  const auto dup = tuning("import " + path("wider.toml") + " --name wider");
  EXPECT_EQ(dup.exit_code, 1);
  EXPECT_NE(dup.output.find("'wider' exists already"), std::string::npos) << dup.output;
}

TEST_F(TuningCli, AnInvalidActiveSetIsRefusedAndTheLastGoodOneRuns) {
  ASSERT_EQ(serve().exit_code, 0);
  ASSERT_EQ(tuning("export paper --out " + path("p.toml")).exit_code, 0);
  ASSERT_EQ(tuning("import " + path("p.toml") + " --name broken --activate").exit_code, 0);
  sql("UPDATE tuning_sets SET b_l = 3.0 WHERE name = 'broken'");  // as a hand edit of the file would
  const auto s = serve();
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("refused tuning set 'broken'"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("tuning set 'paper'"), std::string::npos) << s.output;
}

// A set whose model was identified at another sample period is refused at start like any invalid
// set, and the last good one runs (an outside walk-through's import at Ts 0.01 s had stopped the
// appliance from starting at all).
TEST_F(TuningCli, AnActiveSetAtAnotherSamplePeriodIsRefusedAndTheLastGoodOneRuns) {
  ASSERT_EQ(serve().exit_code, 0);
  ASSERT_EQ(tuning("export paper --out " + path("p.toml")).exit_code, 0);
  std::ifstream in(path("p.toml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const auto at = toml.find("Ts = 0.005");
  ASSERT_NE(at, std::string::npos) << toml;
  toml.replace(at, 10, "Ts = 0.01");
  std::ofstream(path("slow.toml")) << toml;
  ASSERT_EQ(tuning("import " + path("slow.toml") + " --name slow --activate").exit_code, 0);
  const auto s = serve();
  ASSERT_EQ(s.exit_code, 0) << s.output;
  EXPECT_NE(s.output.find("refused tuning set 'slow': its model"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("has Ts 0.01 s, and the loop runs every 0.005 s"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("tuning set 'paper'"), std::string::npos) << s.output;
}

// A set edited over Modbus or HTTP keeps where it came from, and says it was edited since (not
// just "seeded from the configuration" after an edit).
TEST_F(TuningCli, AnEditedSetSaysSoBesideWhereItCameFrom) {
  ASSERT_EQ(serve().exit_code, 0);
  EXPECT_EQ(tuning("show paper").output.find("edited since"), std::string::npos) << "not edited yet";
  // What the store writer does with an accepted lc_mm write: the value and the modified time.
  sql("UPDATE tuning_sets SET lc_mm = 3, modified_ms = created_ms + 60000 WHERE name = 'paper'");
  const auto show = tuning("show paper");
  ASSERT_EQ(show.exit_code, 0) << show.output;
  EXPECT_TRUE(std::regex_search(show.output, std::regex(R"(source: seeded from the configuration[^\n]*; edited since \(the edits: epa tuning audit --since \d+\))")))
      << show.output;
  EXPECT_NE(tuning("list").output.find("; edited since"), std::string::npos);
}

TEST_F(TuningCli, ADamagedDatabaseIsMovedAsideAndTheApplianceStartsInFault) {
  std::ofstream(path("epa.db"), std::ios::binary) << std::string(4096, 'x');
  const auto s = serve();
  ASSERT_EQ(s.exit_code, 4) << s.output;  // the timed run ended in that FAULT (nobody reset it)
  EXPECT_NE(s.output.find("was damaged"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("mode fault"), std::string::npos) << s.output;  // the final status line
  int moved = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir_))
    if (e.path().filename().string().rfind("epa.db.corrupt-", 0) == 0 && std::filesystem::file_size(e.path()) == 4096) ++moved;
  EXPECT_EQ(moved, 1);
  EXPECT_EQ(tuning("list").exit_code, 0);  // the new one is seeded
}

TEST_F(TuningCli, ADatabaseFromANewerEpaStopsTheStartWithAMessage) {
  ASSERT_EQ(serve().exit_code, 0);
  sql("PRAGMA user_version = 42");
  const auto s = serve();
  EXPECT_EQ(s.exit_code, 1);
  EXPECT_NE(s.output.find("schema version 42"), std::string::npos) << s.output;
  EXPECT_NE(tuning("list").output.find("schema version 42"), std::string::npos);
}

TEST_F(TuningCli, TheAuditLogIsFilteredAndBadFiltersAreNamed) {
  ASSERT_EQ(serve().exit_code, 0);
  ASSERT_EQ(tuning("export paper --out " + path("p.toml")).exit_code, 0);
  ASSERT_EQ(tuning("import " + path("p.toml") + " --name b --activate").exit_code, 0);
  EXPECT_NE(tuning("audit --source cli --json").output.find(R"("point":"import_tuning_set")"), std::string::npos);
  EXPECT_NE(tuning("audit --source modbus").output.find("no audit entries match"), std::string::npos);
  EXPECT_NE(tuning("audit --until 2000-01-01").output.find("no audit entries match"), std::string::npos);
  EXPECT_NE(tuning("audit --since 2000-01-01T00:00:00Z --limit 1").output.find("cli"), std::string::npos);
  const auto bad = tuning("audit --since yesterday");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("--since 'yesterday' is not a time"), std::string::npos) << bad.output;
}

TEST_F(TuningCli, NoDatabaseIsNamedNotCreated) {
  const auto o = tuning("list");
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.output.find("no database at " + path("epa.db")), std::string::npos) << o.output;
  EXPECT_FALSE(std::filesystem::exists(path("epa.db")));
}

}  // namespace
