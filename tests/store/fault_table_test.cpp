// The fault history in the store: written by the store thread in its batch, trimmed to
// the newest 64 in the same transaction, counted since the store was created, read by a second
// connection while the writer holds the file, kept across reopening, and added by schema
// migration 4 to a schema-3 file without touching the other tables.
#include "store/fault_table.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "store/audit_log.hpp"
#include "store/retained_points.hpp"
#include "store/run_table.hpp"
#include "store/statement.hpp"
#include "store/store_file.hpp"
#include "store/store_writer.hpp"
#include "store/transaction.hpp"
#include "store/tuning_set_table.hpp"
#include "store_fixture.hpp"

namespace epa::store {
namespace {

using runtime::FaultCode;
using runtime::FaultRecord;
using runtime::Mode;
using testing::paper_seed;

FaultRecord fault(std::int64_t time_ms, FaultCode code, Mode mode, double position_mm) {
  FaultRecord f;
  f.time_ms = time_ms;
  f.code = code;
  f.mode = mode;
  f.position_mm = position_mm;
  f.setpoint_mm = 250.0;
  f.valve_v = 1.5;
  f.sensor_v = position_mm / 50.0;
  f.name = std::string(runtime::to_string(code));
  f.text = std::string(runtime::describe(code));
  return f;
}

class FaultTableTest : public testing::ScratchDir {
 protected:
  std::unique_ptr<StoreWriter> writer(const std::string& file) {
    auto opened = open_store(path(file), paper_seed(), 1000);
    EXPECT_TRUE(opened) << opened.error().message;
    auto running = *TuningSetTable(opened->db).find("paper");
    return std::make_unique<StoreWriter>(std::move(opened->db), running, std::set<points::PointId>{});
  }
  Database reader(const std::string& file) {
    auto db = open_existing_store(path(file));  // as `epa faults` opens it
    EXPECT_TRUE(db) << db.error().message;
    return std::move(*db);
  }
};

TEST_F(FaultTableTest, TheStoreThreadKeepsTheNewestSixtyFourAndCountsThemAll) {
  auto w = writer("epa.db");
  for (int i = 1; i <= 70; ++i) w->record_fault(fault(10'000 + i, FaultCode::kSoftLimit, Mode::kManual, i));
  ASSERT_TRUE(w->flush());
  Database db = reader("epa.db");  // a second connection while the writer holds the file
  auto rows = FaultTable(db).recent(1000);
  ASSERT_TRUE(rows) << rows.error().message;
  ASSERT_EQ(rows->size(), 64u);
  EXPECT_EQ(rows->front().time_ms, 10'070);  // newest first
  EXPECT_EQ(rows->back().time_ms, 10'007);   // the six oldest trimmed
  EXPECT_EQ(*FaultTable(db).count(), 70u);
  {
    auto n = db.prepare("SELECT COUNT(*) FROM fault_history");  // finalized at the brace: its read snapshot ends
    ASSERT_TRUE(n);
    ASSERT_TRUE(*n->step());
    EXPECT_EQ(n->column_int(0), 64);
  }

  w->record_fault(fault(20'000, FaultCode::kHeartbeatLost, Mode::kRun, 10.0));  // a later batch trims again
  ASSERT_TRUE(w->flush());
  rows = FaultTable(db).recent(1000);
  ASSERT_EQ(rows->size(), 64u);
  EXPECT_EQ(rows->front().code, FaultCode::kHeartbeatLost);
  EXPECT_EQ(rows->back().time_ms, 10'008);
  EXPECT_EQ(*FaultTable(db).count(), 71u);
}

TEST_F(FaultTableTest, TheInsertAndTheTrimAreOneChange) {
  auto opened = open_store(path("epa.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened);
  Database& db = opened->db;
  {
    auto tx = Transaction::begin(db);
    ASSERT_TRUE(tx);
    for (int i = 0; i < 64; ++i) ASSERT_TRUE(FaultTable(db).add(fault(i, FaultCode::kSoftLimit, Mode::kRun, 1.0)));
    ASSERT_TRUE(tx->commit());
  }
  {
    auto tx = Transaction::begin(db);
    ASSERT_TRUE(tx);
    ASSERT_TRUE(FaultTable(db).add(fault(100, FaultCode::kIoErrors, Mode::kRun, 1.0)));
    // not committed: rolled back, the trimmed row is back and the new one gone
  }
  auto rows = FaultTable(db).recent(1000);
  ASSERT_EQ(rows->size(), 64u);
  EXPECT_EQ(rows->front().time_ms, 63);
  EXPECT_EQ(rows->back().time_ms, 0);
  EXPECT_EQ(*FaultTable(db).count(), 64u);
}

TEST_F(FaultTableTest, TheHistorySurvivesReopeningWithEveryField) {
  {
    auto w = writer("epa.db");
    w->start();
    w->record_fault(fault(1000, FaultCode::kFollowingError, Mode::kRun, 113.5));
    FaultRecord unread = fault(2000, FaultCode::kStoreDamaged, Mode::kStop, 0.0);
    unread.position_mm = unread.sensor_v = std::nan("");  // nothing read yet
    w->record_fault(unread);
    w->record_fault(fault(3000, FaultCode::kSoftLimit, Mode::kManual, 300.25));
    w->stop();
  }
  auto reopened = open_store(path("epa.db"), paper_seed(), 5000);
  ASSERT_TRUE(reopened) << reopened.error().message;
  EXPECT_FALSE(reopened->created);
  auto rows = FaultTable(reopened->db).recent(10);
  ASSERT_TRUE(rows);
  ASSERT_EQ(rows->size(), 3u);
  const FaultRecord& newest = (*rows)[0];
  EXPECT_EQ(newest.time_ms, 3000);
  EXPECT_EQ(newest.code, FaultCode::kSoftLimit);
  EXPECT_EQ(newest.mode, Mode::kManual);
  EXPECT_EQ(newest.name, "soft-limit");
  EXPECT_EQ(newest.text, "the piston left the soft limits");
  EXPECT_EQ(newest.position_mm, 300.25);
  EXPECT_EQ(newest.setpoint_mm, 250.0);
  EXPECT_EQ(newest.valve_v, 1.5);
  EXPECT_EQ(newest.sensor_v, 300.25 / 50.0);
  EXPECT_EQ((*rows)[1].code, FaultCode::kStoreDamaged);
  EXPECT_TRUE(std::isnan((*rows)[1].position_mm));  // NULL in the file
  EXPECT_TRUE(std::isnan((*rows)[1].sensor_v));
  EXPECT_EQ((*rows)[2].code, FaultCode::kFollowingError);
  EXPECT_EQ((*rows)[2].mode, Mode::kRun);
  EXPECT_EQ(*FaultTable(reopened->db).count(), 3u);
  EXPECT_EQ(FaultTable(reopened->db).recent(2)->size(), 2u);
}

TEST_F(FaultTableTest, MigrationFromASchemaThreeFileKeepsTheOtherTables) {
  {
    auto db = Database::open(path("old.db"), true);
    ASSERT_TRUE(db);
    ASSERT_TRUE(configure_connection(*db));
    ASSERT_TRUE(migrate(*db, 3));
    // The seed as schema 3's own tables held it (today's model table writes columns schema 3 lacks).
    ASSERT_TRUE(db->exec(
        "INSERT INTO models (id, name, created_ms, source, a_json, b_json, m_r, m_l, b_r, b_l, ts_s, mm_per_volt) "
        "VALUES (1, 'paper', 1000, 'paper eq 9-10', '[1.0, -0.9094, -0.611, 0.5204]', '[0.0, 1.024, -2.046, 1.029]', "
        "1.7627, 1.0707, 1.232, -1.722, 0.005, 50.0)"));
    ASSERT_TRUE(db->exec(
        "INSERT INTO tuning_sets (id, name, created_ms, modified_ms, source, model_id, controller, f_json, g_json, h_json, "
        "m_r, m_l, b_r, b_l, lc_mm, valve_limit_v) VALUES (1, 'paper', 1000, 1000, 'paper eq 12-13', 1, 'pp-ffidz', "
        "'[1.0, -1.778, 0.7828]', '[-0.1734, 0.577, -0.3958]', '[-0.1734, 0.577, -0.3958]', 1.7627, 1.0707, 1.232, -1.722, 5.0, 5.0)"));
    ASSERT_TRUE(db->exec("INSERT INTO settings (key, value) VALUES ('active_tuning_set', '1'), ('last_good_tuning_set', '1')"));
    ASSERT_TRUE(AuditLog(*db).append({1500, "cli", "m_r", 1.0, 2.0}));
    ASSERT_TRUE(RunTable(*db).insert({.path = "runs/a.csv", .recorded_ms = 1600, .controller = "pp-ffidz", .samples = 10}));
    ASSERT_TRUE(RetainedPoints(*db).put("setpoint_mm", 120.0, 1700));
    auto t = db->prepare("SELECT name FROM sqlite_master WHERE name = 'fault_history'");
    ASSERT_TRUE(t);
    ASSERT_FALSE(*t->step());  // schema 3 has none
  }
  auto opened = open_store(path("old.db"), paper_seed(), 2000);
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_EQ(opened->migrated_from, 3);
  EXPECT_FALSE(opened->seeded);
  Database& db = opened->db;
  EXPECT_EQ(*schema_version(db), kSchemaVersion);
  EXPECT_EQ(TuningSetTable(db).all()->size(), 1u);
  EXPECT_EQ(*AuditLog(db).count(), 1);
  ASSERT_EQ(RunTable(db).recent(10)->size(), 1u);
  EXPECT_EQ(RunTable(db).recent(10)->front().path, "runs/a.csv");
  EXPECT_EQ(RetainedPoints(db).all()->at("setpoint_mm"), 120.0);
  EXPECT_TRUE(FaultTable(db).recent(10)->empty());
  EXPECT_EQ(*FaultTable(db).count(), 0u);
  {
    auto tx = Transaction::begin(db);
    ASSERT_TRUE(tx);
    ASSERT_TRUE(FaultTable(db).add(fault(3000, FaultCode::kSoftLimit, Mode::kManual, 301.0)));
    ASSERT_TRUE(tx->commit());
  }
  EXPECT_EQ(*FaultTable(db).count(), 1u);
}

}  // namespace
}  // namespace epa::store
