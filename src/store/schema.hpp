#pragma once
// The store's schema and its migrations. PRAGMA user_version is the schema version; each
// migration takes the database from version N-1 to N inside one transaction, so an upgrade is
// applied whole or not at all. A database from a newer epa is refused, never modified.
#include "core/result.hpp"
#include "store/database.hpp"

namespace epa::store {

inline constexpr int kSchemaVersion = 6;

core::Result<int> schema_version(Database& db);

// Brings `db` to `target` (kSchemaVersion by default). Returns the version it started from.
core::Result<int> migrate(Database& db, int target = kSchemaVersion);

// WAL journal, full sync on commit (a committed change survives a power cut), foreign keys.
core::Status configure_connection(Database& db);

}  // namespace epa::store
