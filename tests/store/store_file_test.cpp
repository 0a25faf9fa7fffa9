// Opening the database file in every state it can be found in.
#include "store/store_file.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "store/active_tuning.hpp"
#include "store/audit_log.hpp"
#include "store/statement.hpp"
#include "store/tuning_set_table.hpp"
#include "store_fixture.hpp"

namespace epa::store {
namespace {

namespace fs = std::filesystem;
using testing::paper_seed;

class StoreFile : public testing::ScratchDir {
 protected:
  std::string read_all(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }
};

TEST_F(StoreFile, AMissingFileIsCreatedAndSeeded) {
  auto opened = open_store(path("epa.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_TRUE(opened->created);
  EXPECT_TRUE(opened->seeded);
  EXPECT_TRUE(opened->moved_aside.empty());
  EXPECT_TRUE(fs::exists(path("epa.db")));
  auto active = load_active_tuning(opened->db);
  ASSERT_TRUE(active) << active.error().message;
  EXPECT_EQ(active->set.name, "paper");
  EXPECT_EQ(active->model.name, "paper");
}

TEST_F(StoreFile, AnExistingFileIsReopenedNotReseeded) {
  {
    auto opened = open_store(path("epa.db"), paper_seed(), 1000);
    ASSERT_TRUE(opened);
    ASSERT_TRUE(AuditLog(opened->db).append({1500, "cli", "m_r", 1.0, 2.0}));
  }
  auto again = open_store(path("epa.db"), paper_seed(), 2000);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_FALSE(again->created);
  EXPECT_FALSE(again->seeded);
  EXPECT_EQ(again->migrated_from, kSchemaVersion);
  EXPECT_EQ(*AuditLog(again->db).count(), 1);
  EXPECT_EQ(TuningSetTable(again->db).all()->size(), 1u);
}

TEST_F(StoreFile, AnEmptyFileIsTreatedAsMissing) {
  std::ofstream(path("epa.db")).close();
  auto opened = open_store(path("epa.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_TRUE(opened->created);
  EXPECT_TRUE(opened->seeded);
}

TEST_F(StoreFile, AFileThatIsNotADatabaseIsMovedAsideWithATimestampAndReplaced) {
  const std::string garbage(8192, '\x5a');
  std::ofstream(path("epa.db"), std::ios::binary) << garbage;
  const std::int64_t now_ms = 1'795'000'000'000;  // a fixed time, ms since the epoch
  auto opened = open_store(path("epa.db"), paper_seed(), now_ms);
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_EQ(opened->moved_aside, moved_aside_name(path("epa.db"), now_ms));
  EXPECT_NE(opened->moved_aside.find(".corrupt-2026"), std::string::npos) << opened->moved_aside;
  EXPECT_FALSE(opened->damage.empty());
  EXPECT_EQ(read_all(opened->moved_aside), garbage);  // kept byte for byte, never deleted
  EXPECT_TRUE(opened->created);
  EXPECT_TRUE(opened->seeded);
  EXPECT_TRUE(load_active_tuning(opened->db));
}

TEST_F(StoreFile, ADatabaseWithDamagedPagesIsMovedAside) {
  {
    auto opened = open_store(path("epa.db"), paper_seed(), 1000);
    ASSERT_TRUE(opened);
    ASSERT_TRUE(opened->db.exec("PRAGMA wal_checkpoint(TRUNCATE); PRAGMA journal_mode = DELETE"));
    ASSERT_TRUE(opened->db.exec("BEGIN"));
    for (int i = 0; i < 200; ++i) ASSERT_TRUE(AuditLog(opened->db).append({i, "cli", "m_r", 1.0, 2.0 + i}));
    ASSERT_TRUE(opened->db.exec("COMMIT"));
  }
  // Overwrite the middle of the file (b-tree pages), keeping the header valid.
  std::string bytes = read_all(path("epa.db"));
  ASSERT_GT(bytes.size(), 3 * 4096u);
  for (std::size_t i = 4096; i < bytes.size() - 100; i += 7) bytes[i] = static_cast<char>(i * 31);
  std::ofstream(path("epa.db"), std::ios::binary | std::ios::trunc) << bytes;

  auto opened = open_store(path("epa.db"), paper_seed(), 5000);
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_FALSE(opened->moved_aside.empty());
  EXPECT_TRUE(fs::exists(opened->moved_aside));
  EXPECT_TRUE(opened->seeded);
}

TEST_F(StoreFile, ADatabaseFromANewerEpaIsRefusedAndNotMoved) {
  {
    auto opened = open_store(path("epa.db"), paper_seed(), 1000);
    ASSERT_TRUE(opened);
    ASSERT_TRUE(opened->db.exec("PRAGMA user_version = 7"));
  }
  auto opened = open_store(path("epa.db"), paper_seed(), 2000);
  ASSERT_FALSE(opened);
  EXPECT_NE(opened.error().message.find("schema version 7"), std::string::npos) << opened.error().message;
  EXPECT_TRUE(fs::exists(path("epa.db")));
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().string().find(".corrupt-"), std::string::npos) << entry.path();
}

TEST_F(StoreFile, AnInvalidActiveSetIsRefusedAndTheLastGoodOneUsed) {
  auto opened = open_store(path("epa.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened);
  TuningSetTable sets(opened->db);
  TuningSet broken = *sets.find("paper");
  broken.name = "broken";
  broken.dead_zone.b_l = 2.0;  // b_l > b_r: the compensation cannot be built
  const auto broken_id = *sets.insert(broken);
  ASSERT_TRUE(sets.activate(broken_id));

  auto loaded = load_active_tuning(opened->db);
  ASSERT_TRUE(loaded) << loaded.error().message;
  EXPECT_EQ(loaded->set.name, "paper");
  ASSERT_EQ(loaded->refused.size(), 1u);
  EXPECT_NE(loaded->refused[0].find("'broken'"), std::string::npos) << loaded->refused[0];
  EXPECT_NE(loaded->refused[0].find("b_l"), std::string::npos) << loaded->refused[0];
}

TEST_F(StoreFile, WhenNoSetValidatesLoadingFailsNamingEachRefusal) {
  auto opened = open_store(path("epa.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened);
  ASSERT_TRUE(opened->db.exec("UPDATE tuning_sets SET lc_mm = -1"));
  auto loaded = load_active_tuning(opened->db);
  ASSERT_FALSE(loaded);
  EXPECT_NE(loaded.error().message.find("lc_mm"), std::string::npos) << loaded.error().message;
}

TEST_F(StoreFile, ASetThatLoadsBecomesTheLastGoodOne) {
  auto opened = open_store(path("epa.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened);
  TuningSetTable sets(opened->db);
  TuningSet second = *sets.find("paper");
  second.name = "second";
  const auto id = *sets.insert(second);
  ASSERT_TRUE(sets.activate(id));
  ASSERT_TRUE(load_active_tuning(opened->db));
  EXPECT_EQ(**sets.last_good_id(), id);
}

}  // namespace
}  // namespace epa::store
