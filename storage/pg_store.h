// The store on PostgreSQL, for several keel-server replicas on one database and one shared
// blob folder: the rules of SqlStore over a pool of libpqxx connections. Callers use
// open_store() (storage/open_store.h). What PostgreSQL adds to the rules:
//
// - Row locks: {for_update} and {skip_locked} in the rules' statements are real here, so
//   concurrent leases on any replica never wait for each other or take the same job, and an
//   upload's chunk is written under its row lock (no two replicas write one upload at once).
// - Idempotency-Key is UNIQUE in the database: replicas agree on the first job.
// - Change feed: this replica's listeners get a transaction's changes at once after its
//   commit (never for a rollback); other replicas hear them through pg_notify, sent after
//   the commit in batches, on their LISTEN connection (PgChangeFeed says why).
#pragma once

#include <filesystem>
#include <string>

#include "storage/sql_store.h"

namespace keel::storage {

struct PgStoreOptions {
  std::string database_url;        // postgresql://...
  std::filesystem::path blob_dir;  // shared: blobs/, tmp/, uploads/
  size_t max_connections = 32;     // per replica
  int connect_timeout_s = 5;       // an unreachable host fails after this long
  // Temp and orphan part files younger than this may belong to another replica's write in
  // progress; older ones are left by a crash and removed at open.
  int64_t stale_file_age_s = 3600;
  bool listen = true;  // tell other replicas of changes and hear theirs (NOTIFY/LISTEN)
};

// SqlStore on PostgreSQL (its Sql is in pg_store.cc).
class PgStore : public SqlStore {
 public:
  PgStore(const PgStoreOptions& options, Clock clock);
};

}  // namespace keel::storage
