#include "storage/pg_migrations.h"

#include <string>

#include "storage/open_store.h"

namespace keel::storage {

namespace {

// Version 1: every table of SQLite's versions 1-3. Ids and names sort byte-wise (COLLATE
// "C") whatever the database's locale, as in SQLite. `seq` orders rows by creation.
// jobs.log_next hands out job_logs.seq under the job's row lock, so concurrent writers of
// one job's log never pick the same number.
const char* const kSchema = R"sql(
CREATE TABLE projects (
  name          text COLLATE "C" PRIMARY KEY,
  created_at_ms bigint NOT NULL,
  quota_bytes   bigint NOT NULL DEFAULT 0 CHECK (quota_bytes >= 0)
);
INSERT INTO projects (name, created_at_ms) VALUES ('default', 0);
CREATE TABLE blobs (
  sha256        text COLLATE "C" PRIMARY KEY CHECK (length(sha256) = 64),
  size          bigint NOT NULL CHECK (size >= 0),
  created_at_ms bigint NOT NULL
);
CREATE TABLE uploads (
  id            text COLLATE "C" PRIMARY KEY,
  name          text NOT NULL,
  size          bigint NOT NULL CHECK (size >= 0),
  committed     bigint NOT NULL DEFAULT 0 CHECK (committed >= 0 AND committed <= size),
  created_at_ms bigint NOT NULL,
  project       text COLLATE "C" NOT NULL REFERENCES projects (name)
);
CREATE TABLE missions (
  seq           bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  id            text COLLATE "C" NOT NULL UNIQUE,
  name          text COLLATE "C" NOT NULL,
  bundle_blob   text COLLATE "C" NOT NULL REFERENCES blobs (sha256),
  cad_blob      text COLLATE "C" REFERENCES blobs (sha256),
  cad_name      text NOT NULL DEFAULT '',
  created_at_ms bigint NOT NULL,
  project       text COLLATE "C" NOT NULL REFERENCES projects (name)
);
CREATE TABLE batches (
  seq           bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  id            text COLLATE "C" NOT NULL UNIQUE,
  project       text COLLATE "C" NOT NULL,
  jobs          bigint NOT NULL,
  created_at_ms bigint NOT NULL
);
CREATE TABLE jobs (
  seq                 bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  id                  text COLLATE "C" NOT NULL UNIQUE,
  mission_id          text COLLATE "C" NOT NULL REFERENCES missions (id),
  state               text NOT NULL
                      CHECK (state IN ('queued', 'running', 'succeeded', 'failed', 'canceled')),
  stages              text NOT NULL,
  options             text NOT NULL,
  stage               text NOT NULL DEFAULT '',
  progress            double precision NOT NULL DEFAULT 0,
  error               text NOT NULL DEFAULT '',
  attempts            integer NOT NULL DEFAULT 0,
  lease_expiries      integer NOT NULL DEFAULT 0,
  lease_id            text COLLATE "C",
  lease_expires_at_ms bigint,
  lease_ms            bigint NOT NULL DEFAULT 30000,
  worker              text COLLATE "C" NOT NULL DEFAULT '',
  idempotency_key     text COLLATE "C" UNIQUE,
  created_at_ms       bigint NOT NULL,
  started_at_ms       bigint NOT NULL DEFAULT 0,
  finished_at_ms      bigint NOT NULL DEFAULT 0,
  project             text COLLATE "C" NOT NULL REFERENCES projects (name),
  batch_id            text COLLATE "C" NOT NULL DEFAULT '',
  log_next            bigint NOT NULL DEFAULT 0
);
CREATE TABLE stage_outputs (
  seq             bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  job_id          text COLLATE "C" NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  stage           text COLLATE "C" NOT NULL,
  report          text NOT NULL,
  seconds         double precision NOT NULL,
  completed_at_ms bigint NOT NULL,
  UNIQUE (job_id, stage)
);
CREATE TABLE artifacts (
  seq           bigint GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  id            text COLLATE "C" NOT NULL UNIQUE,
  job_id        text COLLATE "C" NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  stage         text COLLATE "C" NOT NULL,
  name          text COLLATE "C" NOT NULL,
  sha256        text COLLATE "C" NOT NULL REFERENCES blobs (sha256),
  size          bigint NOT NULL,
  created_at_ms bigint NOT NULL,
  UNIQUE (job_id, stage, name)
);
CREATE TABLE job_logs (
  job_id        text COLLATE "C" NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  seq           bigint NOT NULL,
  t_ms          bigint NOT NULL,
  text          text NOT NULL,
  PRIMARY KEY (job_id, seq)
);
CREATE TABLE api_tokens (
  seq           bigint GENERATED ALWAYS AS IDENTITY UNIQUE,
  token_sha256  text COLLATE "C" PRIMARY KEY CHECK (length(token_sha256) = 64),
  id            text COLLATE "C" NOT NULL UNIQUE,
  label         text NOT NULL,
  role          text NOT NULL CHECK (role IN ('admin', 'submitter', 'viewer', 'worker')),
  project       text COLLATE "C" NOT NULL,
  created_at_ms bigint NOT NULL,
  expires_at_ms bigint NOT NULL DEFAULT 0,
  revoked_at_ms bigint NOT NULL DEFAULT 0
);
CREATE TABLE workers (
  id            text COLLATE "C" PRIMARY KEY,
  job_id        text COLLATE "C" NOT NULL DEFAULT '',
  last_seen_ms  bigint NOT NULL
);
-- The lease takes the oldest queued job (of a project): a small partial index each.
CREATE INDEX jobs_queued ON jobs (seq) WHERE state = 'queued';
CREATE INDEX jobs_queued_by_project ON jobs (project, seq) WHERE state = 'queued';
-- requeue_expired_leases scans only running jobs.
CREATE INDEX jobs_running_by_expiry ON jobs (lease_expires_at_ms) WHERE state = 'running';
CREATE INDEX jobs_by_state ON jobs (state, seq);
CREATE INDEX jobs_by_mission ON jobs (mission_id, seq);
CREATE INDEX jobs_by_project ON jobs (project, seq);
CREATE INDEX jobs_by_batch ON jobs (batch_id, seq);
CREATE INDEX jobs_by_finished ON jobs (finished_at_ms);
CREATE INDEX missions_by_name ON missions (name);
CREATE INDEX missions_by_project ON missions (project, seq);
CREATE INDEX artifacts_by_job ON artifacts (job_id, seq);
CREATE INDEX workers_by_last_seen ON workers (last_seen_ms);
)sql";

// Any fixed number: the advisory lock every migrating replica takes.
constexpr const char* kMigrationLock = "SELECT pg_advisory_xact_lock(7311403151)";

int read_version(PgTx& tx) {
  const pqxx::result exists = tx.work().exec(
      "SELECT 1 FROM pg_tables WHERE schemaname = current_schema() "
      "AND tablename = 'schema_version'");
  if (exists.empty()) return 0;
  const pqxx::result row = tx.work().exec("SELECT MAX(version) FROM schema_version");
  return row[0][0].is_null() ? 0 : row[0][0].as<int>();
}

// Version 2 (SQLite's version 4): which project references which blob, for per-project
// usage and quotas and so a token of one project fetches only its blobs.
const char* const kBlobRefs = R"sql(
CREATE TABLE blob_refs (
  project text COLLATE "C" NOT NULL,
  sha256  text COLLATE "C" NOT NULL,
  PRIMARY KEY (project, sha256)
);
INSERT INTO blob_refs (project, sha256) SELECT project, bundle_blob FROM missions
  ON CONFLICT DO NOTHING;
INSERT INTO blob_refs (project, sha256) SELECT project, cad_blob FROM missions
  WHERE cad_blob IS NOT NULL AND cad_blob <> '' ON CONFLICT DO NOTHING;
INSERT INTO blob_refs (project, sha256) SELECT j.project, a.sha256 FROM artifacts a
  JOIN jobs j ON j.id = a.job_id ON CONFLICT DO NOTHING;
)sql";

}  // namespace

const std::vector<Migration>& pg_migrations() {
  static const std::vector<Migration> migrations = {
      {1, "keel schema (SQLite versions 1-3)", kSchema},
      {2, "blob references by project", kBlobRefs},
  };
  return migrations;
}

int pg_schema_version(PgPool& pool) {
  return pool.transact([](PgTx& tx) { return read_version(tx); });
}

int apply_pg_migrations(PgPool& pool, const std::vector<Migration>& migrations) {
  const std::string where = redact_database_url(pool.url());
  int version = pg_schema_version(pool);
  require_applicable(migrations, where, version);
  for (const Migration& migration : migrations) {
    if (migration.version <= version) continue;
    version = pool.transact([&](PgTx& tx) {
      tx.work().exec(kMigrationLock);
      tx.work().exec("CREATE TABLE IF NOT EXISTS schema_version (version integer NOT NULL)");
      // Re-read under the lock: another replica may have migrated meanwhile.
      const int now = read_version(tx);
      require_applicable(migrations, where, now);
      if (now >= migration.version) return now;
      try {
        tx.work().exec(migration.sql);
      } catch (const pqxx::sql_error& error) {
        throw migration_failed(where, migration, error);
      }
      tx.work().exec("DELETE FROM schema_version");
      tx.work().exec("INSERT INTO schema_version (version) VALUES (" +
                     std::to_string(migration.version) + ")");
      return migration.version;
    });
  }
  return version;
}

}  // namespace keel::storage
