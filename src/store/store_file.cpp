#include "store/store_file.hpp"

#include <ctime>
#include <filesystem>
#include <system_error>

#include "core/utc_stamp.hpp"
#include "store/model_table.hpp"
#include "store/schema.hpp"
#include "store/statement.hpp"
#include "store/transaction.hpp"
#include "store/tuning_set_table.hpp"

namespace epa::store {

namespace fs = std::filesystem;

namespace {

bool is_damage(int sqlite_code) {
  const int primary = sqlite_code & 0xff;
  return primary == SQLITE_NOTADB || primary == SQLITE_CORRUPT;
}

// "" when the file passes PRAGMA integrity_check, else what it reported.
core::Result<std::string> integrity_problem(Database& db) {
  auto stmt = db.prepare("PRAGMA integrity_check");
  if (!stmt) return stmt.error();
  std::string report;
  auto s = stmt->each_row([&report](const Statement& row) {
    const std::string line = row.column_text(0);
    if (line != "ok") report += (report.empty() ? "" : "; ") + line;
    return core::ok();
  });
  if (!s) return s.error();
  return report;
}

// Opens and checks an existing or new file. A damaged file gives an Error whose message starts
// with "damaged:", anything else (permissions, newer schema) a plain one.
core::Result<Database> open_checked(const std::string& path, int* migrated_from) {
  auto db = Database::open(path, true);
  if (!db) return db.error();
  auto damaged = [&](const core::Error& e) { return core::Error{e.code, "damaged: " + e.message}; };
  if (auto s = configure_connection(*db); !s) return is_damage(db->last_error_code()) ? damaged(s.error()) : s.error();
  auto problem = integrity_problem(*db);
  if (!problem) return is_damage(db->last_error_code()) ? damaged(problem.error()) : problem.error();
  if (!problem->empty()) return core::Error{core::ErrorCode::kIo, "damaged: integrity check: " + *problem};
  auto from = migrate(*db);
  if (!from) return is_damage(db->last_error_code()) ? damaged(from.error()) : from.error();
  *migrated_from = *from;
  return db;
}

core::Status move_aside(const std::string& path, const std::string& target) {
  std::error_code ec;
  fs::rename(path, target, ec);
  if (ec) return core::io_error("cannot move the damaged database " + path + " aside to " + target + ": " + ec.message());
  for (const char* suffix : {"-wal", "-shm"}) {  // its journal belongs with it
    if (fs::exists(path + suffix)) fs::rename(path + suffix, target + suffix, ec);
  }
  return core::ok();
}

}  // namespace

std::string moved_aside_name(const std::string& path, std::int64_t now_ms) {
  return path + ".corrupt-" + core::utc_stamp(now_ms);
}

core::Status seed_if_empty(Database& db, const StoreSeed& seed, std::int64_t now_ms, bool* seeded) {
  if (seeded) *seeded = false;
  TuningSetTable sets(db);
  auto existing = sets.all();
  if (!existing) return existing.error();
  if (!existing->empty()) return core::ok();
  auto tx = Transaction::begin(db);
  if (!tx) return tx.error();
  ModelRecord model = seed.model;
  model.created_ms = now_ms;
  auto model_id = ModelTable(db).insert(model);
  if (!model_id) return model_id.error();
  TuningSet tuning = seed.tuning;
  tuning.model_id = *model_id;
  tuning.created_ms = tuning.modified_ms = now_ms;
  if (auto s = validate(tuning, model.model); !s) return core::invalid_argument("cannot seed the store: " + s.error().message);
  auto set_id = sets.insert(tuning);
  if (!set_id) return set_id.error();
  if (auto s = sets.activate(*set_id); !s) return s;
  if (auto s = sets.set_last_good(*set_id); !s) return s;
  if (auto s = tx->commit(); !s) return s;
  if (seeded) *seeded = true;
  return core::ok();
}

core::Result<Database> open_existing_store(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return core::io_error("no database at " + path + " (epa serve creates it on its first start)");
  auto db = Database::open(path, false);
  if (!db) return db.error();
  if (auto s = configure_connection(*db); !s) return s.error();
  if (auto from = migrate(*db); !from) return from.error();
  return db;
}

core::Result<OpenedStore> open_store(const std::string& path, const StoreSeed& seed, std::int64_t now_ms) {
  std::error_code ec;
  const bool existed = path != ":memory:" && fs::exists(path, ec) && fs::file_size(path, ec) > 0;
  int migrated_from = 0;
  std::string moved_aside, damage;
  auto db = open_checked(path, &migrated_from);
  if (!db) {
    const std::string& message = db.error().message;
    if (message.rfind("damaged: ", 0) != 0) return db.error();
    // open_checked closed its connection on the way out: move the file aside and start anew.
    damage = message.substr(9);
    moved_aside = moved_aside_name(path, now_ms);
    if (auto s = move_aside(path, moved_aside); !s) return s.error();
    db = open_checked(path, &migrated_from);
    if (!db) return core::io_error("cannot create a new database after moving the damaged one aside: " + db.error().message);
  }
  bool seeded = false;
  if (auto s = seed_if_empty(*db, seed, now_ms, &seeded); !s) return s.error();
  return OpenedStore{.db = std::move(*db), .created = !existed || !moved_aside.empty(), .seeded = seeded,
                     .migrated_from = migrated_from, .moved_aside = moved_aside, .damage = damage};
}

}  // namespace epa::store
