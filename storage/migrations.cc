#include "storage/migrations.h"

#include <stdexcept>

namespace keel::storage {

namespace {

// Version 1: every table. Ids are TEXT with a kind prefix (m_, j_, u_, a_, l_); tables that
// are listed in creation order carry an INTEGER PRIMARY KEY `seq`, which VACUUM keeps stable.
const char* const kCoreTables = R"sql(
CREATE TABLE blobs (
  sha256        TEXT PRIMARY KEY CHECK (length(sha256) = 64),
  size          INTEGER NOT NULL CHECK (size >= 0),
  created_at_ms INTEGER NOT NULL
);
CREATE TABLE uploads (
  id            TEXT PRIMARY KEY,
  name          TEXT NOT NULL,
  size          INTEGER NOT NULL CHECK (size >= 0),
  committed     INTEGER NOT NULL DEFAULT 0 CHECK (committed >= 0 AND committed <= size),
  created_at_ms INTEGER NOT NULL
);
CREATE TABLE missions (
  seq           INTEGER PRIMARY KEY,
  id            TEXT NOT NULL UNIQUE,
  name          TEXT NOT NULL,
  bundle_blob   TEXT NOT NULL REFERENCES blobs (sha256),
  cad_blob      TEXT REFERENCES blobs (sha256),
  cad_name      TEXT NOT NULL DEFAULT '',
  created_at_ms INTEGER NOT NULL
);
CREATE TABLE jobs (
  seq                 INTEGER PRIMARY KEY,
  id                  TEXT NOT NULL UNIQUE,
  mission_id          TEXT NOT NULL REFERENCES missions (id),
  state               TEXT NOT NULL
                      CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'canceled')),
  stages              TEXT NOT NULL,
  options             TEXT NOT NULL,
  stage               TEXT NOT NULL DEFAULT '',
  progress            REAL NOT NULL DEFAULT 0,
  error               TEXT NOT NULL DEFAULT '',
  attempts            INTEGER NOT NULL DEFAULT 0,
  lease_expiries      INTEGER NOT NULL DEFAULT 0,
  lease_id            TEXT,
  lease_expires_at_ms INTEGER,
  lease_ms            INTEGER NOT NULL DEFAULT 30000,
  worker              TEXT NOT NULL DEFAULT '',
  idempotency_key     TEXT UNIQUE,
  created_at_ms       INTEGER NOT NULL,
  started_at_ms       INTEGER NOT NULL DEFAULT 0,
  finished_at_ms      INTEGER NOT NULL DEFAULT 0
);
CREATE TABLE stage_outputs (
  seq           INTEGER PRIMARY KEY,
  job_id        TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  stage         TEXT NOT NULL,
  report        TEXT NOT NULL,
  seconds       REAL NOT NULL,
  completed_at_ms INTEGER NOT NULL,
  UNIQUE (job_id, stage)
);
CREATE TABLE artifacts (
  seq           INTEGER PRIMARY KEY,
  id            TEXT NOT NULL UNIQUE,
  job_id        TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  stage         TEXT NOT NULL,
  name          TEXT NOT NULL,
  sha256        TEXT NOT NULL REFERENCES blobs (sha256),
  size          INTEGER NOT NULL,
  created_at_ms INTEGER NOT NULL,
  UNIQUE (job_id, stage, name)
);
CREATE TABLE job_logs (
  job_id        TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  seq           INTEGER NOT NULL,
  t_ms          INTEGER NOT NULL,
  text          TEXT NOT NULL,
  PRIMARY KEY (job_id, seq)
) WITHOUT ROWID;
CREATE TABLE api_tokens (
  token_sha256  TEXT PRIMARY KEY CHECK (length(token_sha256) = 64),
  label         TEXT NOT NULL,
  created_at_ms INTEGER NOT NULL
);
)sql";

// Version 2: indexes for the listings and the lease query (oldest queued job first).
const char* const kListingIndexes = R"sql(
CREATE INDEX jobs_by_state ON jobs (state, seq);
CREATE INDEX jobs_by_mission ON jobs (mission_id, seq);
CREATE INDEX missions_by_name ON missions (name);
CREATE INDEX artifacts_by_job ON artifacts (job_id, seq);
)sql";

// Version 3: projects and roles (every object in a project; tokens with a role, a project,
// an expiry and revocation; existing data moves into 'default' and existing tokens become
// admin tokens of every project), reprocess batches, and the workers seen by the queue.
// Columns are added with defaults rather than REFERENCES: SQLite refuses a REFERENCES
// column with a non-NULL default when foreign keys are on; the store checks projects itself.
const char* const kProjectsAndRoles = R"sql(
CREATE TABLE projects (
  name          TEXT PRIMARY KEY,
  created_at_ms INTEGER NOT NULL,
  quota_bytes   INTEGER NOT NULL DEFAULT 0 CHECK (quota_bytes >= 0)
);
INSERT INTO projects (name, created_at_ms) VALUES ('default', 0);
ALTER TABLE uploads ADD COLUMN project TEXT NOT NULL DEFAULT 'default';
ALTER TABLE missions ADD COLUMN project TEXT NOT NULL DEFAULT 'default';
ALTER TABLE jobs ADD COLUMN project TEXT NOT NULL DEFAULT 'default';
ALTER TABLE jobs ADD COLUMN batch_id TEXT NOT NULL DEFAULT '';
CREATE TABLE batches (
  seq           INTEGER PRIMARY KEY,
  id            TEXT NOT NULL UNIQUE,
  project       TEXT NOT NULL,
  jobs          INTEGER NOT NULL,
  created_at_ms INTEGER NOT NULL
);
ALTER TABLE api_tokens ADD COLUMN id TEXT;
ALTER TABLE api_tokens ADD COLUMN role TEXT NOT NULL DEFAULT 'admin'
  CHECK (role IN ('admin', 'submitter', 'viewer', 'worker'));
ALTER TABLE api_tokens ADD COLUMN project TEXT NOT NULL DEFAULT '*';
ALTER TABLE api_tokens ADD COLUMN expires_at_ms INTEGER NOT NULL DEFAULT 0;
ALTER TABLE api_tokens ADD COLUMN revoked_at_ms INTEGER NOT NULL DEFAULT 0;
UPDATE api_tokens SET id = 't_' || substr(token_sha256, 1, 16);
CREATE UNIQUE INDEX api_tokens_by_id ON api_tokens (id);
CREATE TABLE workers (
  id            TEXT PRIMARY KEY,
  job_id        TEXT NOT NULL DEFAULT '',
  last_seen_ms  INTEGER NOT NULL
);
CREATE INDEX jobs_by_project ON jobs (project, seq);
CREATE INDEX jobs_by_batch ON jobs (batch_id, seq);
CREATE INDEX jobs_by_finished ON jobs (finished_at_ms);
CREATE INDEX missions_by_project ON missions (project, seq);
)sql";

// Version 4: which project references which blob, for per-project usage and quotas and so
// a token of one project fetches only its blobs. Existing missions and artifacts are read in.
const char* const kBlobRefs = R"sql(
CREATE TABLE blob_refs (
  project TEXT NOT NULL,
  sha256  TEXT NOT NULL,
  PRIMARY KEY (project, sha256)
) WITHOUT ROWID;
INSERT OR IGNORE INTO blob_refs (project, sha256) SELECT project, bundle_blob FROM missions;
INSERT OR IGNORE INTO blob_refs (project, sha256)
  SELECT project, cad_blob FROM missions WHERE cad_blob IS NOT NULL AND cad_blob <> '';
INSERT OR IGNORE INTO blob_refs (project, sha256)
  SELECT j.project, a.sha256 FROM artifacts a JOIN jobs j ON j.id = a.job_id;
)sql";

void record_version(Database& db, int version) {
  auto statement = db.cached("UPDATE schema_version SET version = ?1");
  statement->bind_int64(1, version).run();
}

}  // namespace

const std::vector<Migration>& sqlite_migrations() {
  static const std::vector<Migration> migrations = {
      {1, "core tables", kCoreTables},
      {2, "listing indexes", kListingIndexes},
      {3, "projects, roles, batches and workers", kProjectsAndRoles},
      {4, "blob references by project", kBlobRefs},
  };
  return migrations;
}

void require_applicable(const std::vector<Migration>& migrations, const std::string& where,
                        int version) {
  for (size_t i = 0; i < migrations.size(); ++i)
    if (migrations[i].version != static_cast<int>(i + 1))
      throw std::logic_error("migration '" + migrations[i].name + "' has version " +
                             std::to_string(migrations[i].version) + ", expected " +
                             std::to_string(i + 1));
  const int newest = static_cast<int>(migrations.size());
  if (version > newest)
    throw SchemaTooNew(where + ": schema version " + std::to_string(version) +
                       " is newer than this program knows (" + std::to_string(newest) +
                       "); use a newer keel-server");
}

std::runtime_error migration_failed(const std::string& where, const Migration& migration,
                                    const std::exception& error) {
  return std::runtime_error(where + ": migration " + std::to_string(migration.version) + " (" +
                            migration.name + ") failed: " + error.what());
}

int schema_version(Database& db) {
  auto exists =
      db.cached("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'schema_version'");
  if (!exists->step()) return 0;
  auto statement = db.cached("SELECT MAX(version) FROM schema_version");
  return statement->step() ? static_cast<int>(statement->column_int64(0)) : 0;
}

int apply_migrations(Database& db, const std::vector<Migration>& migrations) {
  {
    Transaction transaction(db);
    db.exec("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)");
    db.exec("INSERT INTO schema_version SELECT 0 WHERE NOT EXISTS (SELECT 1 FROM schema_version)");
    transaction.commit();
  }
  int version = schema_version(db);
  require_applicable(migrations, db.file().string(), version);
  for (const Migration& migration : migrations) {
    if (migration.version <= version) continue;
    Transaction transaction(db);
    // Re-read inside the write lock: another process may have migrated meanwhile.
    if (schema_version(db) >= migration.version) continue;
    try {
      db.exec(migration.sql);
    } catch (const std::exception& error) {
      throw migration_failed(db.file().string(), migration, error);
    }
    record_version(db, migration.version);
    transaction.commit();
    version = migration.version;
  }
  return version;
}

}  // namespace keel::storage
