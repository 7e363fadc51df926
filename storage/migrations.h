// The SQLite schema as an ordered list of migrations. The database records the applied
// version in `schema_version`; opening applies only the missing ones, each in its own
// transaction, so a crash mid-migration leaves the previous version intact.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "storage/sqlite_db.h"

namespace keel::storage {

// The database was made by a newer program (its schema version is beyond ours): opening it
// would misread it, so it is refused.
struct SchemaTooNew : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Migration {
  int version;       // 1, 2, 3, ... in order; never renumber or edit a released one
  std::string name;  // what it does, for errors and logs
  std::string sql;   // one or more statements
};

// What applying migrations checks first, the same way for each database: the list is
// numbered 1, 2, 3, ... (std::logic_error) and the database `where` names, at `version`, is
// not newer than the list (SchemaTooNew).
void require_applicable(const std::vector<Migration>& migrations, const std::string& where,
                        int version);
// The error of a migration that failed, naming the database, the migration and why.
std::runtime_error migration_failed(const std::string& where, const Migration& migration,
                                    const std::exception& error);

// Keel's migrations, oldest first.
const std::vector<Migration>& sqlite_migrations();

// The version recorded in `schema_version` (0 for a fresh database).
int schema_version(Database& db);

// Applies the migrations newer than the database's version, each in one transaction, and
// returns the resulting version. Throws when the database is newer than `migrations`
// (a downgrade would misread it) or when the list is not numbered 1, 2, 3, ...
int apply_migrations(Database& db, const std::vector<Migration>& migrations);

}  // namespace keel::storage
