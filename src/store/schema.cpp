#include "store/schema.hpp"

#include "core/audit.hpp"

#include <array>

#include "store/statement.hpp"
#include "store/transaction.hpp"

namespace epa::store {

static_assert(core::kAuditMinRows == 1000, "migration 5's trigger keeps the newest 1000 rows");

namespace {

// Migration N (index N-1) takes the schema from version N-1 to N. Append, never edit a shipped one.
constexpr std::array<const char*, kSchemaVersion> kMigrations = {
    // 1: models, tuning sets with the active one, the append-only audit log.
    R"sql(
CREATE TABLE models (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  created_ms INTEGER NOT NULL,
  source TEXT NOT NULL,              -- the paper, or identified from which runs
  a_json TEXT NOT NULL,              -- ARX A, coefficients of q^0, q^-1, ... (output in sensor volts)
  b_json TEXT NOT NULL,              -- ARX B (input: valve volts after the dead zone)
  m_r REAL NOT NULL, m_l REAL NOT NULL, b_r REAL NOT NULL, b_l REAL NOT NULL,  -- dead zone (eq 2), V
  ts_s REAL NOT NULL CHECK (ts_s > 0),
  mm_per_volt REAL NOT NULL CHECK (mm_per_volt > 0),
  fit_json TEXT NOT NULL DEFAULT '{}' -- fit figures and training runs, as epa identify reports them
);
CREATE TABLE tuning_sets (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  created_ms INTEGER NOT NULL,
  modified_ms INTEGER NOT NULL,
  source TEXT NOT NULL,
  model_id INTEGER NOT NULL REFERENCES models(id),
  controller TEXT NOT NULL CHECK (controller IN ('pp', 'pp-ngidz', 'pp-ffidz')),
  f_json TEXT NOT NULL, g_json TEXT NOT NULL, h_json TEXT NOT NULL,  -- RST polynomials in q^-1
  design_json TEXT NOT NULL DEFAULT '{}',  -- the design spec that produced F, G, H
  m_r REAL NOT NULL, m_l REAL NOT NULL, b_r REAL NOT NULL, b_l REAL NOT NULL,  -- compensation, V
  lc_mm REAL NOT NULL,
  valve_limit_v REAL NOT NULL
);
CREATE TABLE settings (key TEXT PRIMARY KEY, value TEXT NOT NULL);  -- active_tuning_set, last_good_tuning_set
CREATE TABLE audit_log (
  id INTEGER PRIMARY KEY,
  time_ms INTEGER NOT NULL,
  source TEXT NOT NULL,              -- "modbus 10.0.0.5:50312", "web 10.0.0.7", "cli"
  point TEXT NOT NULL,
  old_value REAL,                    -- NULL: not a number
  new_value REAL
);
CREATE INDEX audit_log_time ON audit_log(time_ms);
CREATE TRIGGER audit_log_no_update BEFORE UPDATE ON audit_log BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
CREATE TRIGGER audit_log_no_delete BEFORE DELETE ON audit_log BEGIN SELECT RAISE(ABORT, 'the audit log is append-only'); END;
)sql",
    // 2: recorded runs, and the retained values of persisted points that are not tuning (setpoint).
    R"sql(
CREATE TABLE runs (
  id INTEGER PRIMARY KEY,
  path TEXT NOT NULL,
  recorded_ms INTEGER NOT NULL,
  controller TEXT NOT NULL,
  tuning_set_id INTEGER REFERENCES tuning_sets(id),
  samples INTEGER NOT NULL,
  ts_s REAL NOT NULL,
  from_mm REAL, to_mm REAL,
  rise_s REAL, settling_s REAL, ess_mm REAL, overshoot_pct REAL  -- NULL: never reached
);
CREATE TABLE retained_points (point TEXT PRIMARY KEY, value REAL NOT NULL, changed_ms INTEGER NOT NULL);
)sql",
    // 3: the fourth controller, pp-traj, and its parameters. SQLite cannot change a CHECK in place:
    // the table is rebuilt (its rows, ids and the runs that name them kept; the references are
    // checked at COMMIT, when tuning_sets exists again under its name).
    R"sql(
PRAGMA defer_foreign_keys = ON;
CREATE TABLE tuning_sets_v3 (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  created_ms INTEGER NOT NULL,
  modified_ms INTEGER NOT NULL,
  source TEXT NOT NULL,
  model_id INTEGER NOT NULL REFERENCES models(id),
  controller TEXT NOT NULL CHECK (controller IN ('pp', 'pp-ngidz', 'pp-ffidz', 'pp-traj')),
  f_json TEXT NOT NULL, g_json TEXT NOT NULL, h_json TEXT NOT NULL,  -- RST polynomials in q^-1
  design_json TEXT NOT NULL DEFAULT '{}',  -- the design spec that produced F, G, H
  m_r REAL NOT NULL, m_l REAL NOT NULL, b_r REAL NOT NULL, b_l REAL NOT NULL,  -- compensation, V
  lc_mm REAL NOT NULL,
  valve_limit_v REAL NOT NULL,
  trajectory_json TEXT NOT NULL DEFAULT '{}'  -- pp-traj's parameters (store/trajectory_settings.hpp)
);
INSERT INTO tuning_sets_v3 (id, name, created_ms, modified_ms, source, model_id, controller, f_json, g_json, h_json,
                            design_json, m_r, m_l, b_r, b_l, lc_mm, valve_limit_v)
  SELECT id, name, created_ms, modified_ms, source, model_id, controller, f_json, g_json, h_json,
         design_json, m_r, m_l, b_r, b_l, lc_mm, valve_limit_v FROM tuning_sets;
DROP TABLE tuning_sets;
ALTER TABLE tuning_sets_v3 RENAME TO tuning_sets;
)sql",
    // 4: the fault history: each fault the loop latched, with its cause; the store thread
    // keeps the newest 64 (store/fault_table.hpp). AUTOINCREMENT: an id is never reused, so the
    // newest id is the number of faults since the store was created.
    R"sql(
CREATE TABLE fault_history (
  id INTEGER PRIMARY KEY AUTOINCREMENT,
  time_ms INTEGER NOT NULL,          -- when it latched, unix ms (wall clock)
  code INTEGER NOT NULL,             -- the fault code, as the fault_code register
  name TEXT NOT NULL,                -- "following-error"
  text TEXT NOT NULL,                -- the sentence for an operator, as written then
  mode INTEGER NOT NULL,             -- the mode it was in before the fault, as the mode register (0 stop, 1 run, 2 manual, 4 excite)
  position_mm REAL, setpoint_mm REAL, valve_v REAL, sensor_v REAL  -- NULL: not known (nothing read yet)
);
)sql",
    // 5: a retention for the audit log ([store] audit_max_rows): the oldest rows may be deleted,
    // never the newest 1000 (core::kAuditMinRows); rows are still never changed.
    R"sql(
DROP TRIGGER audit_log_no_delete;
CREATE TRIGGER audit_log_keeps_newest BEFORE DELETE ON audit_log
  WHEN OLD.id > (SELECT max(id) FROM audit_log) - 1000
  BEGIN SELECT RAISE(ABORT, 'the audit log keeps its newest 1000 rows'); END;
)sql",
    // 6: what a model knows of the axis beyond the Hammerstein model (store/axis_json.hpp): the
    // verdict, the drive range, the stick-slip model and its spread. Older models get '{}': nothing
    // known, so the Hammerstein model describes their axis as before.
    R"sql(
ALTER TABLE models ADD COLUMN axis_json TEXT NOT NULL DEFAULT '{}';
)sql",
};

}  // namespace

core::Result<int> schema_version(Database& db) {
  auto stmt = db.prepare("PRAGMA user_version");
  if (!stmt) return stmt.error();
  auto row = stmt->step();
  if (!row) return row.error();
  return static_cast<int>(stmt->column_int(0));
}

core::Result<int> migrate(Database& db, int target) {
  auto from = schema_version(db);
  if (!from) return from;
  if (*from > kSchemaVersion)
    return core::invalid_argument(db.path() + " has schema version " + std::to_string(*from) +
                                  ", newer than this epa understands (" + std::to_string(kSchemaVersion) +
                                  "): refusing to use it; run a newer epa or point [store] path at another file");
  for (int v = *from + 1; v <= target; ++v) {
    auto tx = Transaction::begin(db);
    if (!tx) return tx.error();
    if (auto s = db.exec(kMigrations[static_cast<std::size_t>(v - 1)]); !s)
      return core::io_error("migration to schema version " + std::to_string(v) + " failed: " + s.error().message);
    if (auto s = db.exec("PRAGMA user_version = " + std::to_string(v)); !s) return s.error();
    if (auto s = tx->commit(); !s) return s.error();
  }
  return *from;
}

core::Status configure_connection(Database& db) {
  // WAL: readers (epa tuning, a backup) never block the store thread; synchronous=FULL: a commit
  // is on disk when COMMIT returns, which is what the saved counter promises.
  if (auto s = db.exec("PRAGMA foreign_keys = ON; PRAGMA synchronous = FULL"); !s) return s;
  auto mode = db.prepare("PRAGMA journal_mode = WAL");
  if (!mode) return mode.error();
  auto row = mode->step();
  if (!row) return row.error();
  const std::string got = mode->column_text(0);
  if (got != "wal" && got != "memory") return core::io_error(db.path() + ": cannot switch to WAL journal mode (got " + got + ")");
  return core::ok();
}

}  // namespace epa::store
