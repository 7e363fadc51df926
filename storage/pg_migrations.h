// The PostgreSQL schema as an ordered list of migrations, with the discipline of the SQLite
// one (storage/migrations.h): `schema_version` records the applied version, each missing
// migration runs in its own transaction, a newer database is refused (SchemaTooNew).
// Several keel-server replicas may start at once: each migration transaction holds an
// advisory lock and re-reads the version under it, so exactly one replica applies it.
#pragma once

#include <vector>

#include "storage/migrations.h"
#include "storage/pg_connection.h"

namespace keel::storage {

// Keel's PostgreSQL migrations, oldest first. Version 1 is the content of SQLite's
// versions 1-3 (projects, roles, batches, workers) written as PostgreSQL DDL.
const std::vector<Migration>& pg_migrations();

// The version recorded in `schema_version` (0 for a database Keel never opened).
int pg_schema_version(PgPool& pool);

// Applies the migrations newer than the database's version and returns the resulting one.
int apply_pg_migrations(PgPool& pool, const std::vector<Migration>& migrations);

}  // namespace keel::storage
