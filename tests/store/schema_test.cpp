#include "store/schema.hpp"

#include <gtest/gtest.h>

#include "store/audit_log.hpp"
#include "store/model_table.hpp"
#include "store/retained_points.hpp"
#include "store/run_table.hpp"
#include "store/statement.hpp"
#include "store/store_file.hpp"
#include "store/tuning_set_table.hpp"
#include "store_fixture.hpp"

namespace epa::store {
namespace {

using testing::paper_seed;

Database memory() {
  auto db = Database::open(":memory:", true);
  EXPECT_TRUE(db);
  return std::move(*db);
}

TEST(Schema, AFreshDatabaseMigratesFromZeroToTheCurrentVersion) {
  Database db = memory();
  auto from = migrate(db);
  ASSERT_TRUE(from) << from.error().message;
  EXPECT_EQ(*from, 0);
  EXPECT_EQ(*schema_version(db), kSchemaVersion);
  EXPECT_EQ(*migrate(db), kSchemaVersion);  // a second run changes nothing
}

// Every earlier version, with data in it, migrates to the current one with the data intact.
TEST(Schema, EachEarlierVersionMigratesWithItsDataKept) {
  for (int version = 1; version < kSchemaVersion; ++version) {
    SCOPED_TRACE("from version " + std::to_string(version));
    Database db = memory();
    ASSERT_TRUE(migrate(db, version));
    ASSERT_EQ(*schema_version(db), version);
    ASSERT_TRUE(seed_if_empty(db, paper_seed(), 1234));
    ASSERT_TRUE(AuditLog(db).append({1500, "cli", "m_r", 1.0, 2.0}));

    auto from = migrate(db);
    ASSERT_TRUE(from) << from.error().message;
    EXPECT_EQ(*from, version);
    EXPECT_EQ(*schema_version(db), kSchemaVersion);
    auto sets = TuningSetTable(db).all();
    ASSERT_TRUE(sets);
    ASSERT_EQ(sets->size(), 1u);
    EXPECT_EQ(sets->front().name, "paper");
    EXPECT_EQ(sets->front().created_ms, 1234);
    EXPECT_EQ(*AuditLog(db).count(), 1);
    // What the later versions added works on the migrated file.
    EXPECT_TRUE(RunTable(db).insert({.path = "runs/a.csv", .controller = "pp"}));
    EXPECT_TRUE(RetainedPoints(db).put("setpoint_mm", 100.0, 2000));
  }
}

TEST(Schema, ADatabaseFromANewerEpaIsRefusedAndLeftAlone) {
  Database db = memory();
  ASSERT_TRUE(db.exec("PRAGMA user_version = 99"));
  auto r = migrate(db);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("schema version 99"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("newer"), std::string::npos);
  EXPECT_EQ(*schema_version(db), 99);
}

class SchemaFile : public testing::ScratchDir {};

TEST_F(SchemaFile, AFileDatabaseRunsInWalModeWithFullSync) {
  auto db = Database::open(path("epa.db"), true);
  ASSERT_TRUE(db);
  ASSERT_TRUE(configure_connection(*db));
  auto mode = db->prepare("PRAGMA journal_mode");
  ASSERT_TRUE(mode);
  ASSERT_TRUE(*mode->step());
  EXPECT_EQ(mode->column_text(0), "wal");
  auto sync = db->prepare("PRAGMA synchronous");
  ASSERT_TRUE(sync);
  ASSERT_TRUE(*sync->step());
  EXPECT_EQ(sync->column_int(0), 2);  // FULL
}

}  // namespace
}  // namespace epa::store
