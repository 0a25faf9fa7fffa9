// The tables: models, tuning sets with the active one, the audit log, runs, retained points.
#include <gtest/gtest.h>

#include <cmath>

#include "core/model_file.hpp"
#include "store/audit_log.hpp"
#include "store/axis_json.hpp"
#include "store/database.hpp"
#include "store/model_table.hpp"
#include "store/retained_points.hpp"
#include "store/run_table.hpp"
#include "store/statement.hpp"
#include "store/transaction.hpp"
#include "store/tuning_points.hpp"
#include "store/tuning_set_table.hpp"
#include "store_fixture.hpp"

namespace epa::store {
namespace {

using testing::paper_seed;
using testing::seeded_memory_db;

TEST(ModelTable, AModelRoundTripsWithItsProvenance) {
  Database db = seeded_memory_db();
  ModelRecord m = paper_seed().model;
  m.name = "identified";
  m.source = "identified from runs/a.csv, runs/b.csv";
  m.fit_json = R"({"fit_pct":91.2})";
  m.model.A = core::Polynomial({1.0, -0.5, 0.1234567890123});
  m.model.Ts = 0.01;
  auto id = ModelTable(db).insert(m);
  ASSERT_TRUE(id) << id.error().message;
  auto back = ModelTable(db).get(*id);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->name, "identified");
  EXPECT_EQ(back->source, m.source);
  EXPECT_EQ(back->fit_json, m.fit_json);
  EXPECT_EQ(back->model.A.coefficients(), m.model.A.coefficients());  // exact: JSON keeps every digit
  EXPECT_EQ(back->model.B.coefficients(), m.model.B.coefficients());
  EXPECT_EQ(back->model.Ts, 0.01);
  EXPECT_EQ(back->model.dead_zone.b_l, m.model.dead_zone.b_l);
  EXPECT_EQ(ModelTable(db).all()->size(), 2u);
}

TEST(ModelTable, DuplicateNamesAndInvalidModelsAreRefusedByName) {
  Database db = seeded_memory_db();
  auto dup = ModelTable(db).insert(paper_seed().model);
  ASSERT_FALSE(dup);
  EXPECT_NE(dup.error().message.find("'paper' exists"), std::string::npos) << dup.error().message;
  ModelRecord bad = paper_seed().model;
  bad.name = "bad";
  bad.model.A = core::Polynomial({2.0, 0.1});  // not monic
  auto r = ModelTable(db).insert(bad);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("model 'bad'"), std::string::npos) << r.error().message;
  EXPECT_FALSE(ModelTable(db).get(42));
}

// Every field a model file can say of the axis, compared exactly.
void expect_same_axis(const ModelRecord& actual, const ModelRecord& expected) {
  EXPECT_EQ(actual.axis_model, expected.axis_model);
  EXPECT_EQ(actual.identified_drive_v, expected.identified_drive_v);
  EXPECT_EQ(actual.stick_slip, expected.stick_slip);
  EXPECT_EQ(actual.stick_slip_spread, expected.stick_slip_spread);
}

TEST(ModelTable, AStickSlipModelRoundTripsWithItsSpreadVerdictAndDriveRange) {
  Database db = seeded_memory_db();
  const ModelRecord m = testing::stick_slip_model_record();
  auto id = ModelTable(db).insert(m);
  ASSERT_TRUE(id) << id.error().message;
  auto back = ModelTable(db).get(*id);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_TRUE(back->stick_slip);
  expect_same_axis(*back, m);
  EXPECT_EQ(back->stick_slip->delay_samples, 2);
  EXPECT_EQ(back->model.A.coefficients(), m.model.A.coefficients());
  auto seeded = ModelTable(db).get(1);  // the paper's, seeded without one
  ASSERT_TRUE(seeded);
  EXPECT_FALSE(seeded->stick_slip);
  EXPECT_EQ(seeded->axis_model, core::AxisModel::kHammerstein);
  auto column = db.prepare("SELECT axis_json FROM models WHERE id = 1");
  ASSERT_TRUE(column && *column->step());
  EXPECT_EQ(column->column_text(0), "{}");  // nothing known, as a model from before schema 6
}

TEST(ModelTable, AStoredAxisJsonThatDoesNotParseOrValidateIsRefusedNamingTheModelAndTheField) {
  Database db = seeded_memory_db();
  const ModelRecord m = testing::stick_slip_model_record();
  auto id = ModelTable(db).insert(m);
  ASSERT_TRUE(id) << id.error().message;
  const std::string good = axis_json_text(m);
  auto replaced = [&good](const std::string& from, const std::string& to) {
    std::string text = good;
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from << " not in " << good;
    return at == std::string::npos ? text : text.replace(at, from.size(), to);
  };
  struct Case {
    std::string axis_json, expected;
  };
  const Case cases[] = {
      {"not json", "axis_json is not a JSON object"},
      {"[1, 2]", "axis_json is not a JSON object"},
      {R"({"friction": 1.0})", "unknown key 'friction'"},
      {replaced("\"coulomb_mm\"", "\"mass_kg\":1.0,\"coulomb_mm\""), "unknown key 'stick_slip.mass_kg'"},
      {replaced("\"coulomb_mm\":5.0,", ""), "stick_slip.coulomb_mm is missing"},
      {replaced("\"coulomb_mm\":5.0", "\"coulomb_mm\":\"five\""), "stick_slip.coulomb_mm must be a number"},
      {replaced("\"coulomb_mm\":5.0", "\"coulomb_mm\":9.0"), "static_mm must be >= coulomb_mm"},
      {replaced("\"delay_samples\":2", "\"delay_samples\":1.5"), "stick_slip.delay_samples must be a whole number"},
      {replaced("\"delay_samples\":2", "\"delay_samples\":9"), "stick_slip.delay_samples is outside 0..8"},
      {replaced("\"break_v\":0.11", "\"break_v\":-0.11"), "stick_slip_spread: stick-slip spread: break_v"},
      {replaced("\"stick-slip\"", "\"friction\""), "axis_model must be"},
      {R"({"axis_model": "stick-slip"})", "axis_model \"stick-slip\" needs a stick_slip model"},
      {R"({"stick_slip_spread": {"friction_log_ratio": 0.3, "flow_gain_log_ratio": 0.1, "break_v": 0.1, "spool_lag_s": 0.01,
          "delay_samples": 1.0}})",
       "stick_slip_spread needs a stick_slip model"},
      {R"({"identified_drive_v": [1.0, 2.0]})", "identified_drive_v must be"},
      {R"({"identified_drive_v": [-1.0]})", "identified_drive_v must be"},
  };
  const std::string what = "model " + std::to_string(*id) + " ('rig-2'): axis_json";
  for (const auto& c : cases) {
    auto update = db.prepare("UPDATE models SET axis_json = ? WHERE id = ?");
    ASSERT_TRUE(update);
    update->bind(1, c.axis_json).bind(2, *id);
    ASSERT_TRUE(update->run());
    auto got = ModelTable(db).get(*id);
    ASSERT_FALSE(got) << c.axis_json;
    EXPECT_NE(got.error().message.find(what), std::string::npos) << got.error().message;
    EXPECT_NE(got.error().message.find(c.expected), std::string::npos) << got.error().message;
    EXPECT_FALSE(ModelTable(db).all()) << "every model is read the same way";
  }
}

TEST(ModelTable, AnInsertRefusesWhatAModelFileWouldRefuseNamingTheField) {
  Database db = seeded_memory_db();
  ModelRecord no_model = testing::stick_slip_model_record();
  no_model.stick_slip.reset();
  auto r = ModelTable(db).insert(no_model);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("model 'rig-2': stick_slip_spread needs a stick_slip model"), std::string::npos) << r.error().message;
  ModelRecord sticky = testing::stick_slip_model_record();
  sticky.stick_slip->static_mm = 1.0;  // below the sliding friction
  r = ModelTable(db).insert(sticky);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("static_mm"), std::string::npos) << r.error().message;
  ModelRecord wide = testing::stick_slip_model_record();
  wide.identified_drive_v = std::array<double, 2>{-12.0, 3.0};
  r = ModelTable(db).insert(wide);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("identified_drive_v"), std::string::npos) << r.error().message;
  EXPECT_EQ(ModelTable(db).all()->size(), 1u) << "nothing stored";
}

// Two models that differ only in what they say of the axis are two models: a set designed on one
// must not end up pointing at the other.
TEST(ModelTable, TheSameDynamicsLookupTellsApartModelsDifferingOnlyInTheirStickSlipModel) {
  Database db = seeded_memory_db();
  ModelTable models(db);
  const ModelRecord m = testing::stick_slip_model_record();
  auto first = models.find_or_insert(m);
  ASSERT_TRUE(first) << first.error().message;
  EXPECT_NE(*first, 1) << "the seeded paper model has the same A, B, dead zone, but no stick-slip model";
  EXPECT_EQ(*models.find_or_insert(m), *first) << "the identical model is reused";

  ModelRecord other = m;
  other.stick_slip->coulomb_mm = 4.0;
  auto second = models.find_or_insert(other);
  ASSERT_TRUE(second) << second.error().message;
  EXPECT_NE(*second, *first);
  EXPECT_EQ(models.get(*second)->name, "rig-2 #2");
  EXPECT_EQ(models.get(*second)->stick_slip->coulomb_mm, 4.0);

  ModelRecord spread = m;
  spread.stick_slip_spread->friction_log_ratio = 0.5;
  ModelRecord verdict = m;
  verdict.axis_model = core::AxisModel::kHammerstein;
  ModelRecord drive = m;
  drive.identified_drive_v = std::array<double, 2>{-3.0, 3.0};
  for (const ModelRecord* r : {&spread, &verdict, &drive}) {
    auto id = models.find_or_insert(*r);
    ASSERT_TRUE(id) << id.error().message;
    EXPECT_NE(*id, *first);
    EXPECT_NE(*id, *second);
  }
  ModelRecord plain = m;  // the same Hammerstein model, nothing known of the axis: the paper's
  plain.axis_model = core::AxisModel::kHammerstein;
  plain.identified_drive_v.reset();
  plain.stick_slip.reset();
  plain.stick_slip_spread.reset();
  EXPECT_EQ(*models.find_or_insert(plain), 1);
  EXPECT_EQ(models.all()->size(), 6u);
}

// The epa-model/1 view of a record and the record of a model file carry every field, also through
// the model file's text (what epa design --save reads, epa identify --save keeps).
TEST(ModelRecord, TheModelFileViewAndTheRecordOfAModelFileCarryTheStickSlipModel) {
  const ModelRecord m = testing::stick_slip_model_record();
  const core::ModelFile file = model_file_of(m);
  EXPECT_EQ(file.source, m.source);
  EXPECT_EQ(file.axis_model, core::AxisModel::kStickSlip);
  EXPECT_EQ(file.stick_slip, m.stick_slip);
  EXPECT_EQ(file.stick_slip_spread, m.stick_slip_spread);
  EXPECT_EQ(file.identified_drive_v, m.identified_drive_v);
  auto parsed = core::parse_model_toml(core::format_model_toml(file), "rig-2.toml");
  ASSERT_TRUE(parsed) << parsed.error().message;
  const ModelRecord back = model_record_of(*parsed, "rig-2", R"({"fit_pct":90.0})");
  EXPECT_EQ(back.name, "rig-2");
  EXPECT_EQ(back.source, m.source);
  EXPECT_EQ(back.fit_json, R"({"fit_pct":90.0})");
  EXPECT_EQ(back.id, 0);
  EXPECT_EQ(back.model.B.coefficients(), m.model.B.coefficients());
  expect_same_axis(back, m);
}

TEST(TuningSetTable, SetsAreFoundByIdOrNameAndUpdatedInPlace) {
  Database db = seeded_memory_db();
  TuningSetTable sets(db);
  auto paper = sets.find("paper");
  ASSERT_TRUE(paper) << paper.error().message;
  EXPECT_EQ(sets.find(std::to_string(paper->id))->name, "paper");
  EXPECT_EQ(paper->F.coefficients(), core::paper::F().coefficients());

  TuningSet copy = *paper;
  copy.name = "slow";
  copy.controller = control::ControllerKind::kPp;
  auto id = sets.insert(copy);
  ASSERT_TRUE(id);
  copy.id = *id;
  copy.dead_zone.m_r = 2.5;
  copy.modified_ms = 9000;
  ASSERT_TRUE(sets.update(copy));
  auto back = sets.get(*id);
  EXPECT_EQ(back->dead_zone.m_r, 2.5);
  EXPECT_EQ(back->modified_ms, 9000);
  EXPECT_EQ(back->controller, control::ControllerKind::kPp);
  EXPECT_EQ(sets.get(paper->id)->dead_zone.m_r, paper->dead_zone.m_r);  // the other set is untouched

  auto missing = sets.find("nope");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("'nope'"), std::string::npos);
}

TEST(TuningSetTable, DuplicateNamesUnknownModelsAndUnknownSetsAreRefused) {
  Database db = seeded_memory_db();
  TuningSetTable sets(db);
  TuningSet t = *sets.find("paper");
  auto dup = sets.insert(t);
  ASSERT_FALSE(dup);
  EXPECT_NE(dup.error().message.find("exists already"), std::string::npos);
  t.name = "orphan";
  t.model_id = 77;
  auto orphan = sets.insert(t);
  ASSERT_FALSE(orphan);
  EXPECT_NE(orphan.error().message.find("model 77"), std::string::npos) << orphan.error().message;
  EXPECT_FALSE(sets.activate(77));
}

TEST(TuningSetTable, OneSetIsActive) {
  Database db = seeded_memory_db();
  TuningSetTable sets(db);
  TuningSet t = *sets.find("paper");
  const auto paper_id = t.id;
  EXPECT_EQ(**sets.active_id(), paper_id);
  t.name = "second";
  const auto second = *sets.insert(t);
  ASSERT_TRUE(sets.activate(second));
  EXPECT_EQ(**sets.active_id(), second);
  EXPECT_EQ(**sets.last_good_id(), paper_id);  // last good changes only when the appliance loads one
}

TEST(AuditLog, EntriesAreAppendOnly) {
  Database db = seeded_memory_db();
  AuditLog log(db);
  ASSERT_TRUE(log.append({1000, "modbus 127.0.0.1:5000", "m_r", 1.7627, 1.9}));
  auto update = db.exec("UPDATE audit_log SET new_value = 0");
  ASSERT_FALSE(update);
  EXPECT_NE(update.error().message.find("append-only"), std::string::npos) << update.error().message;
  EXPECT_FALSE(db.exec("DELETE FROM audit_log"));
  EXPECT_EQ(*log.count(), 1);
  EXPECT_EQ(log.query({})->front().entry.new_value, 1.9);
}

TEST(AuditLog, TheRetentionDropsTheOldestRowsButNeverTheNewestThousand) {
  Database db = seeded_memory_db();
  AuditLog log(db);
  for (int i = 0; i < 1500; ++i) ASSERT_TRUE(log.append({1000 + i, "modbus 127.0.0.1:5000", "setpoint_mm", i * 1.0, i + 1.0}));
  // A retention below the floor keeps the floor.
  EXPECT_EQ(*log.drop_oldest(10), 500);
  EXPECT_EQ(*log.count(), core::kAuditMinRows);
  EXPECT_EQ(log.query({.limit = 1})->front().entry.new_value, 1500.0);  // the newest is kept
  // Nothing but the retention may delete: a plain DELETE of the newest rows is refused.
  auto del = db.exec("DELETE FROM audit_log");
  ASSERT_FALSE(del);
  EXPECT_NE(del.error().message.find("newest 1000"), std::string::npos) << del.error().message;
  EXPECT_EQ(*log.count(), core::kAuditMinRows);
  for (int i = 0; i < 300; ++i) ASSERT_TRUE(log.append({5000 + i, "web 127.0.0.1", "mode", 0, 1}));
  EXPECT_EQ(*log.drop_oldest(1200), 100);
  EXPECT_EQ(*log.count(), 1200);
}

TEST(RunTable, TheRetentionKeepsTheNewestRows) {
  Database db = seeded_memory_db();
  RunTable runs(db);
  for (int i = 0; i < 30; ++i) {
    RunRecord r;
    r.path = "runs/move-" + std::to_string(i) + ".csv";
    r.recorded_ms = 1000 + i;
    r.controller = "pp";
    r.samples = 10;
    r.Ts = 0.005;
    ASSERT_TRUE(runs.insert(r));
  }
  EXPECT_EQ(*runs.drop_oldest(20), 10);
  const auto left = *runs.recent(100);
  ASSERT_EQ(left.size(), 20u);
  EXPECT_EQ(left.front().path, "runs/move-29.csv");
  EXPECT_EQ(left.back().path, "runs/move-10.csv");
}

TEST(AuditLog, FiltersSelectByTimeSourcePointAndLimitNewestFirst) {
  Database db = seeded_memory_db();
  AuditLog log(db);
  ASSERT_TRUE(log.append({1000, "modbus 10.0.0.5:5000", "m_r", 1.0, 2.0}));
  ASSERT_TRUE(log.append({2000, "web 10.0.0.7", "setpoint_mm", 0.0, 50.0}));
  ASSERT_TRUE(log.append({3000, "modbus 10.0.0.6:5001", "setpoint_mm", 50.0, 80.0}));
  ASSERT_TRUE(log.append({4000, "cli", "active_tuning_set", 1.0, 2.0}));

  auto all = log.query({});
  ASSERT_EQ(all->size(), 4u);
  EXPECT_EQ(all->front().entry.unix_time_ms, 4000);  // newest first
  EXPECT_EQ(log.query({.since_ms = 2000, .until_ms = 3000})->size(), 2u);
  EXPECT_EQ(log.query({.source = "modbus"})->size(), 2u);
  EXPECT_EQ(log.query({.source = "10.0.0.7"})->front().entry.point, "setpoint_mm");
  EXPECT_EQ(log.query({.point = "setpoint_mm"})->size(), 2u);
  EXPECT_EQ(log.query({.source = "modbus", .point = "setpoint_mm"})->front().entry.new_value, 80.0);
  EXPECT_EQ(log.query({.limit = 1})->size(), 1u);
  EXPECT_EQ(log.query({.source = "' OR 1=1 --"})->size(), 0u);  // filters are parameters, not SQL
}

TEST(AuditLog, NotANumberIsKeptAsNull) {
  Database db = seeded_memory_db();
  AuditLog log(db);
  ASSERT_TRUE(log.append({1000, "modbus", "setpoint_mm", std::nan(""), 5.0}));
  const auto e = log.query({})->front().entry;
  EXPECT_TRUE(std::isnan(e.old_value));
  EXPECT_EQ(e.new_value, 5.0);
}

TEST(RunTable, RunsKeepTheirMetricsAndNeverReachedOnesStayAbsent) {
  Database db = seeded_memory_db();
  RunTable runs(db);
  ASSERT_TRUE(runs.insert({.path = "runs/move-1.csv", .recorded_ms = 1000, .controller = "pp-ffidz", .tuning_set_id = 1,
                           .samples = 4000, .Ts = 0.005, .from_mm = 0.0, .to_mm = 50.0, .rise_s = 0.24,
                           .settling_s = std::nullopt, .ess_mm = 0.9, .overshoot_pct = 1.5}));
  ASSERT_TRUE(runs.insert({.path = "runs/move-2.csv", .recorded_ms = 2000, .controller = "pp"}));
  auto recent = runs.recent(10);
  ASSERT_EQ(recent->size(), 2u);
  const auto& first = recent->back();
  EXPECT_EQ(first.path, "runs/move-1.csv");
  EXPECT_EQ(first.tuning_set_id, 1);
  EXPECT_EQ(first.rise_s, 0.24);
  EXPECT_FALSE(first.settling_s);
  EXPECT_EQ(first.samples, 4000);
}

TEST(RetainedPoints, ALaterValueReplacesAnEarlierOne) {
  Database db = seeded_memory_db();
  RetainedPoints retained(db);
  ASSERT_TRUE(retained.put("setpoint_mm", 100.0, 1000));
  ASSERT_TRUE(retained.put("setpoint_mm", 120.0, 2000));
  auto all = retained.all();
  ASSERT_EQ(all->size(), 1u);
  EXPECT_EQ(all->at("setpoint_mm"), 120.0);
}

TEST(Transaction, ATransactionNotCommittedLeavesNothingBehind) {
  Database db = seeded_memory_db();
  {
    auto tx = Transaction::begin(db);
    ASSERT_TRUE(tx);
    ASSERT_TRUE(AuditLog(db).append({1000, "cli", "m_r", 1.0, 2.0}));
    ASSERT_TRUE(RetainedPoints(db).put("setpoint_mm", 1.0, 1000));
  }  // no commit: rolled back
  EXPECT_EQ(*AuditLog(db).count(), 0);
  EXPECT_TRUE(RetainedPoints(db).all()->empty());
}

TEST(Database, ErrorsNameTheStatementAndSqlitesReason) {
  Database db = seeded_memory_db();
  auto bad = db.prepare("SELECT * FROM no_such_table");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("no_such_table"), std::string::npos) << bad.error().message;
  auto missing = Database::open("/nonexistent-dir/epa.db", true);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent-dir/epa.db"), std::string::npos);
}

// An accepted tuning write edits the running set's value in the point's own unit (mm for l_c and
// the hold band), through the same point -> value map as the write gate.
TEST(TuningPoints, AWriteEditsTheSetsValueInThePointsUnit) {
  TuningSet set;
  EXPECT_TRUE(apply_tuning_point(set, points::PointId::kLc, 7.5));
  EXPECT_EQ(set.lc_mm, 7.5);
  EXPECT_TRUE(apply_tuning_point(set, points::PointId::kTrajHoldBand, 0.25));
  EXPECT_EQ(set.trajectory.hold_band_mm, 0.25);
  EXPECT_TRUE(apply_tuning_point(set, points::PointId::kBl, -0.5));
  EXPECT_EQ(set.dead_zone.b_l, -0.5);
  EXPECT_TRUE(apply_tuning_point(set, points::PointId::kController, 0));
  EXPECT_EQ(set.controller, control::ControllerKind::kPp);
  EXPECT_FALSE(apply_tuning_point(set, points::PointId::kController, 1.5));
  EXPECT_FALSE(apply_tuning_point(set, points::PointId::kSetpoint, 1.0));
}

// The law gets the set's lengths in sensor volts at the model's scale, the rest as the set has them.
TEST(TuningPoints, TheLawGetsTheSetsLengthsInSensorVolts) {
  TuningSet set;
  set.lc_mm = 6.0;
  set.dead_zone.m_r = 1.3;
  core::HammersteinModel model;
  model.mm_per_volt = 40.0;
  const auto law = controller_config(set, model, 0.0);
  EXPECT_EQ(law.lc_v, 6.0 / 40.0);
  EXPECT_EQ(law.trajectory.hold_band_v, set.trajectory.hold_band_mm / 40.0);
  EXPECT_EQ(law.dead_zone.m_r, 1.3);
}

}  // namespace
}  // namespace epa::store
