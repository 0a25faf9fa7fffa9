#include "store/store_writer.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "store/audit_log.hpp"
#include "store/retained_points.hpp"
#include "store/run_table.hpp"
#include "store/statement.hpp"
#include "store/store_file.hpp"
#include "store/tuning_set_table.hpp"
#include "store_fixture.hpp"

namespace epa::store {
namespace {

using testing::paper_seed;

using P = points::PointId;
const std::set<P> kPersisted = {P::kSetpoint, P::kController, P::kMr, P::kMl, P::kBr, P::kBl, P::kLc};

class StoreWriterTest : public testing::ScratchDir {
 protected:
  void SetUp() override {
    ScratchDir::SetUp();
    auto opened = open_store(path("epa.db"), paper_seed(), 1000);
    ASSERT_TRUE(opened) << opened.error().message;
    running_ = *TuningSetTable(opened->db).find("paper");
    writer_ = std::make_unique<StoreWriter>(std::move(opened->db), running_, kPersisted);
  }
  // A second connection, as `epa tuning` or an inspector would read the file.
  Database reader() {
    auto db = Database::open(path("epa.db"), false);
    EXPECT_TRUE(db);
    return std::move(*db);
  }
  TuningSet running_;
  std::unique_ptr<StoreWriter> writer_;
};

TEST_F(StoreWriterTest, AChangeIsOnDiskWhenTheSavedCounterSaysSo) {
  writer_->record({{2000, "modbus 127.0.0.1:5000", "m_r", 1.7627, 2.0}, {2000, "modbus 127.0.0.1:5000", "b_r", 1.232, 1.3}});
  EXPECT_EQ(writer_->counters().accepted, 1u);
  EXPECT_EQ(writer_->counters().saved, 0u);
  ASSERT_TRUE(writer_->flush());
  EXPECT_EQ(writer_->counters().saved, 1u);

  Database db = reader();
  auto set = TuningSetTable(db).get(running_.id);
  EXPECT_EQ(set->dead_zone.m_r, 2.0);
  EXPECT_EQ(set->dead_zone.b_r, 1.3);
  EXPECT_EQ(set->modified_ms, 2000);
  EXPECT_EQ(*AuditLog(db).count(), 2);
}

TEST_F(StoreWriterTest, PersistedPointsAreKeptOthersOnlyAudited) {
  writer_->record({{2000, "web 127.0.0.1", "setpoint_mm", 0.0, 120.0}});
  writer_->record({{2100, "modbus 127.0.0.1:5000", "mode", 0.0, 1.0}});
  writer_->record({{2200, "modbus 127.0.0.1:5000", "controller", 2.0, 0.0}});
  ASSERT_TRUE(writer_->flush());
  Database db = reader();
  EXPECT_EQ(RetainedPoints(db).all()->at("setpoint_mm"), 120.0);
  EXPECT_FALSE(RetainedPoints(db).all()->contains("mode"));
  EXPECT_EQ(TuningSetTable(db).get(running_.id)->controller, control::ControllerKind::kPp);
  EXPECT_EQ(*AuditLog(db).count(), 3);
  EXPECT_EQ(writer_->counters().saved, 3u);
}

TEST_F(StoreWriterTest, APointNotPersistedInTheMapDoesNotChangeTheSet) {
  Database db0 = reader();
  auto opened = open_store(path("other.db"), paper_seed(), 1000);
  ASSERT_TRUE(opened);
  StoreWriter writer(std::move(opened->db), running_, {P::kSetpoint});
  writer.record({{2000, "modbus", "m_r", 1.7627, 2.0}});
  ASSERT_TRUE(writer.flush());
  auto db = Database::open(path("other.db"), false);
  EXPECT_EQ(TuningSetTable(*db).find("paper")->dead_zone.m_r, running_.dead_zone.m_r);
  EXPECT_EQ(*AuditLog(*db).count(), 1);
}

TEST_F(StoreWriterTest, RunsGoToTheHistoryWithTheRunningSet) {
  writer_->record_run({.path = "runs/move-1.csv", .recorded_ms = 3000, .controller = "pp-ffidz", .samples = 10});
  ASSERT_TRUE(writer_->flush());
  Database db = reader();
  auto runs = RunTable(db).recent(5);
  ASSERT_EQ(runs->size(), 1u);
  EXPECT_EQ(runs->front().tuning_set_id, running_.id);
  EXPECT_EQ(writer_->counters().saved, 0u);  // a run is not a parameter change
}

// A database that refuses writes (read-only, disk full): nothing is dropped, the counter does
// not advance, and everything is written, in order, once writes work again.
TEST_F(StoreWriterTest, AFailedWriteKeepsTheChangesAndRetries) {
  Database blocker = reader();
  ASSERT_TRUE(blocker.exec("BEGIN EXCLUSIVE"));  // holds the write lock: the writer's BEGIN fails (busy)
  writer_->record({{2000, "modbus", "m_r", 1.7627, 2.0}});
  writer_->record({{2001, "modbus", "m_r", 2.0, 2.5}});
  EXPECT_FALSE(writer_->flush());
  EXPECT_EQ(writer_->counters().saved, 0u);
  EXPECT_FALSE(writer_->health().ok);
  EXPECT_EQ(writer_->health().pending, 2u);
  EXPECT_FALSE(writer_->health().last_error.empty());
  ASSERT_TRUE(blocker.exec("COMMIT"));

  ASSERT_TRUE(writer_->flush());
  EXPECT_TRUE(writer_->health().ok);
  EXPECT_EQ(writer_->counters().saved, 2u);
  Database db = reader();
  EXPECT_EQ(TuningSetTable(db).get(running_.id)->dead_zone.m_r, 2.5);  // the later write wins
  auto audit = AuditLog(db).query({});
  ASSERT_EQ(audit->size(), 2u);
  EXPECT_EQ(audit->front().entry.new_value, 2.5);
}

TEST_F(StoreWriterTest, TheThreadSavesABurstWithinASecond) {
  writer_->start();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 1000; ++i) writer_->record({{2000 + i, "modbus", "m_r", 1.0, 1.0 + i * 1e-3}});
  auto elapsed = [&] { return std::chrono::steady_clock::now() - t0; };
  while (writer_->counters().saved < 1000 && elapsed() < std::chrono::seconds(10))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(writer_->counters().saved, 1000u);
  EXPECT_LT(elapsed(), std::chrono::seconds(1));
  writer_->stop();
  Database db = reader();
  EXPECT_EQ(*AuditLog(db).count(), 1000);
  EXPECT_DOUBLE_EQ(TuningSetTable(db).get(running_.id)->dead_zone.m_r, 1.0 + 999 * 1e-3);
}

TEST_F(StoreWriterTest, StopWritesWhatIsPending) {
  writer_->start();
  writer_->record({{2000, "modbus", "b_l", -1.722, -1.8}});
  writer_->stop();
  EXPECT_EQ(writer_->counters().saved, 1u);
  Database db = reader();
  EXPECT_EQ(TuningSetTable(db).get(running_.id)->dead_zone.b_l, -1.8);
}

}  // namespace
}  // namespace epa::store
