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
// The rows written as that version's own tables were (not through today's code, which knows only
// the current columns): a model, a tuning set, an audit entry, and from version 2 a run that names
// the set, so the rebuild of tuning_sets in version 3 has a reference to keep.
void write_version_rows(Database& db, int version) {
  ASSERT_TRUE(db.exec(
      "INSERT INTO models (id, name, created_ms, source, a_json, b_json, m_r, m_l, b_r, b_l, ts_s, mm_per_volt) "
      "VALUES (1, 'paper', 1234, 'paper eq 9-10', '[1.0, -0.9094, -0.611, 0.5204]', '[0.0, 1.024, -2.046, 1.029]', "
      "1.7627, 1.0707, 1.232, -1.722, 0.005, 50.0)"));
  ASSERT_TRUE(db.exec(
      "INSERT INTO tuning_sets (id, name, created_ms, modified_ms, source, model_id, controller, f_json, g_json, h_json, "
      "m_r, m_l, b_r, b_l, lc_mm, valve_limit_v) VALUES (7, 'paper', 1234, 1234, 'seeded', 1, 'pp-ffidz', "
      "'[1.0, -1.7654, 0.7702]', '[-0.1855, 0.5747, -0.3892]', '[-0.1855, 0.5747, -0.3892]', 1.7627, 1.0707, 1.232, -1.722, 5.0, 5.0)"));
  ASSERT_TRUE(db.exec("INSERT INTO settings (key, value) VALUES ('active_tuning_set', '7')"));
  ASSERT_TRUE(AuditLog(db).append({1500, "cli", "m_r", 1.0, 2.0}));
  if (version >= 2) {
    ASSERT_TRUE(db.exec("INSERT INTO runs (path, recorded_ms, controller, tuning_set_id, samples, ts_s) "
                        "VALUES ('runs/old.csv', 1600, 'pp-ffidz', 7, 10, 0.005)"));
  }
}

TEST(Schema, EachEarlierVersionMigratesWithItsDataKept) {
  for (int version = 1; version < kSchemaVersion; ++version) {
    SCOPED_TRACE("from version " + std::to_string(version));
    Database db = memory();
    ASSERT_TRUE(migrate(db, version));
    ASSERT_EQ(*schema_version(db), version);
    write_version_rows(db, version);

    auto from = migrate(db);
    ASSERT_TRUE(from) << from.error().message;
    EXPECT_EQ(*from, version);
    EXPECT_EQ(*schema_version(db), kSchemaVersion);
    auto sets = TuningSetTable(db).all();
    ASSERT_TRUE(sets) << sets.error().message;
    ASSERT_EQ(sets->size(), 1u);
    EXPECT_EQ(sets->front().id, 7);
    EXPECT_EQ(sets->front().name, "paper");
    EXPECT_EQ(sets->front().created_ms, 1234);
    EXPECT_EQ(sets->front().controller, control::ControllerKind::kPpFfidz);
    EXPECT_EQ(sets->front().trajectory, TrajectorySettings{});  // the defaults, where there were none
    EXPECT_EQ(*AuditLog(db).count(), 1);
    // What the later versions added works on the migrated file, references to the set included.
    EXPECT_TRUE(RunTable(db).insert({.path = "runs/a.csv", .controller = "pp-traj", .tuning_set_id = 7}));
    EXPECT_TRUE(RetainedPoints(db).put("setpoint_mm", 100.0, 2000));
    auto changed = sets->front();
    changed.controller = control::ControllerKind::kPpTraj;
    changed.trajectory.hold_band_mm = 0.1;
    ASSERT_TRUE(TuningSetTable(db).update(changed));
    EXPECT_EQ(TuningSetTable(db).get(7)->trajectory.hold_band_mm, 0.1);
    EXPECT_EQ(TuningSetTable(db).get(7)->controller, control::ControllerKind::kPpTraj);
    auto check = db.prepare("PRAGMA foreign_key_check");
    ASSERT_TRUE(check);
    EXPECT_FALSE(*check->step()) << "a reference broken by the migration";
  }
}

// Schema 6 adds what a model knows of the axis; a model stored before it knows nothing: '{}', read
// as the Hammerstein model alone.
TEST(Schema, ModelsFromSchemaFiveMigrateKnowingNoStickSlipModel) {
  Database db = memory();
  ASSERT_TRUE(migrate(db, 5));
  write_version_rows(db, 5);
  ASSERT_TRUE(migrate(db));
  auto column = db.prepare("SELECT axis_json FROM models WHERE id = 1");
  ASSERT_TRUE(column);
  ASSERT_TRUE(*column->step());
  EXPECT_EQ(column->column_text(0), "{}");
  auto model = ModelTable(db).get(1);
  ASSERT_TRUE(model) << model.error().message;
  EXPECT_EQ(model->name, "paper");
  EXPECT_EQ(model->model.dead_zone.b_r, 1.232);
  EXPECT_EQ(model->axis_model, core::AxisModel::kHammerstein);
  EXPECT_FALSE(model->stick_slip);
  EXPECT_FALSE(model->stick_slip_spread);
  EXPECT_FALSE(model->identified_drive_v);
  EXPECT_FALSE(model_file_of(*model).stick_slip);
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
