// SqliteStore: construction and recovery, uploads, blobs, missions, tokens and metrics.
// Jobs, leases, artifacts and logs are in sqlite_store_jobs.cc.
#include "storage/sqlite_store.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <system_error>

#include "storage/ids.h"
#include "storage/migrations.h"
#include "core/sha256.h"
#include "storage/sqlite_queries.h"
#include "storage/store_rules.h"

namespace keel::storage {

namespace fs = std::filesystem;

namespace {

const fs::path& ensure_directory(const fs::path& dir) {
  fs::create_directories(dir);
  return dir;
}

using namespace rules;

}  // namespace

int64_t system_clock_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(system_clock::now().time_since_epoch()).count();
}

std::unique_ptr<Store> open_sqlite_store(const fs::path& data_dir, Clock clock) {
  return std::make_unique<SqliteStore>(data_dir, std::move(clock));
}

SqliteStore::SqliteStore(const fs::path& data_dir, Clock clock)
    : data_dir_(ensure_directory(data_dir)),
      clock_(clock ? std::move(clock) : Clock(system_clock_ms)),
      blobs_(data_dir_ / "blobs", data_dir_ / "tmp"),
      uploads_(data_dir_ / "uploads"),
      writer_(std::make_unique<Database>(data_dir_ / "keel.db")),
      readers_(data_dir_ / "keel.db", DatabaseOptions{5000, /*query_only=*/true}) {
  apply_migrations(*writer_, sqlite_migrations());
  // Recovery (temp files of cut writes, uncommitted upload bytes) is for the first process
  // on the folder only: a second one (`keel-server token ...` while the server runs) must
  // not cut files the live server is writing. An exclusive flock held for the store's
  // lifetime tells which one is first; the kernel drops it when the process dies.
  lock_fd_ = ::open((data_dir_ / "keel.lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ >= 0 && ::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    return;
  }
  blobs_.clear_tmp();
  recover_uploads();
}

SqliteStore::~SqliteStore() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

// --- uploads ---

std::mutex& SqliteStore::upload_lock(const std::string& upload_id) {
  return upload_locks_[std::hash<std::string>{}(upload_id) % upload_locks_.size()];
}

void SqliteStore::recover_uploads() {
  write([&](Database& db) {
    std::vector<proto::Upload> open;
    {
      auto statement = db.cached("SELECT id, committed FROM uploads");
      while (statement->step()) {
        proto::Upload upload;
        upload.id = statement->column_text(0);
        upload.offset = statement->column_int64(1);
        open.push_back(upload);
      }
    }
    for (const proto::Upload& upload : open) {
      // A chunk written and fsynced whose offset never committed (killed in between)
      // leaves the file longer than the committed offset: cut it so a resume is exact.
      const int64_t kept = uploads_.truncate_to(upload.id, upload.offset);
      if (kept < upload.offset) {
        // Committed bytes are gone (the file was damaged): resume from what is there.
        auto statement = db.cached("UPDATE uploads SET committed = ?2 WHERE id = ?1");
        statement->bind_text(1, upload.id).bind_int64(2, kept).run();
      }
    }
    for (const std::string& id : uploads_.part_ids())
      if (!find_upload(db, id)) uploads_.remove(id);
  });
}

proto::Upload SqliteStore::create_upload(const proto::UploadRequest& request) {
  require_upload_size(request.size);
  proto::Upload upload;
  upload.id = new_id(kUploadPrefix);
  upload.name = request.name;
  upload.size = request.size;
  std::lock_guard<std::mutex> lock(upload_lock(upload.id));
  uploads_.create(upload.id);  // the file first: a crash before the row leaves an orphan
  try {
    write([&](Database& db) {
      upload.project = project_of_request(db, request.project);
      auto statement = db.cached(
          "INSERT INTO uploads (id, name, size, committed, created_at_ms, project) "
          "VALUES (?1, ?2, ?3, 0, ?4, ?5)");
      statement->bind_text(1, upload.id)
          .bind_text(2, upload.name)
          .bind_int64(3, upload.size)
          .bind_int64(4, clock_())
          .bind_text(5, upload.project)
          .run();
    });
  } catch (...) {
    uploads_.remove(upload.id);
    throw;
  }
  return upload;
}

proto::Upload SqliteStore::get_upload(const std::string& upload_id) {
  auto upload = read([&](Database& db) { return find_upload(db, upload_id); });
  if (!upload) throw upload_not_found(upload_id);
  return *upload;
}

proto::Upload SqliteStore::append_upload(const std::string& upload_id, int64_t offset,
                                         const char* data, size_t size) {
  std::lock_guard<std::mutex> lock(upload_lock(upload_id));
  proto::Upload upload = get_upload(upload_id);
  if (offset != upload.offset)
    throw OffsetMismatch("upload " + upload_id + ": chunk starts at byte " +
                             std::to_string(offset) + " but " + std::to_string(upload.offset) +
                             " bytes are committed; resume from byte " +
                             std::to_string(upload.offset),
                         upload.offset);
  if (size > static_cast<uint64_t>(upload.size - upload.offset))
    throw Invalid("upload " + upload_id + ": chunk of " + std::to_string(size) + " bytes at byte " +
                  std::to_string(offset) + " ends beyond the announced size of " +
                  std::to_string(upload.size) + " bytes");
  const int64_t kept = uploads_.truncate_to(upload_id, offset);
  if (kept < offset) {
    // Committed bytes vanished from the part file (damaged or removed by hand): move the
    // offset back so the client resumes from what is really there.
    write([&](Database& db) {
      auto statement = db.cached("UPDATE uploads SET committed = ?2 WHERE id = ?1");
      statement->bind_text(1, upload_id).bind_int64(2, kept).run();
    });
    throw OffsetMismatch("upload " + upload_id + ": the part file holds only " +
                             std::to_string(kept) + " of " + std::to_string(offset) +
                             " committed bytes; resume from byte " + std::to_string(kept),
                         kept);
  }
  // Durable bytes first, then the offset: a crash in between leaves extra bytes in the file
  // that the next append or open cuts, never a committed offset without its bytes.
  uploads_.write_chunk(upload_id, offset, data, size);
  const int64_t committed = offset + static_cast<int64_t>(size);
  write([&](Database& db) {
    auto statement =
        db.cached("UPDATE uploads SET committed = ?3 WHERE id = ?1 AND committed = ?2");
    statement->bind_text(1, upload_id).bind_int64(2, offset).bind_int64(3, committed).run();
    if (db.changes() != 1) throw upload_not_found(upload_id);
  });
  upload.offset = committed;
  return upload;
}

void SqliteStore::discard_upload(const std::string& upload_id) {
  write([&](Database& db) {
    auto statement = db.cached("DELETE FROM uploads WHERE id = ?1");
    statement->bind_text(1, upload_id).run();
  });
  uploads_.remove(upload_id);
}

std::string SqliteStore::complete_upload(const std::string& upload_id, const std::string& sha256) {
  require_sha256(sha256, "sha256");
  std::lock_guard<std::mutex> lock(upload_lock(upload_id));
  const proto::Upload upload = get_upload(upload_id);
  const int64_t actual_size = uploads_.truncate_to(upload_id, upload.offset);
  if (actual_size != upload.size) {
    discard_upload(upload_id);
    throw SizeMismatch("upload " + upload_id + " (" + upload.name + "): expected " +
                       std::to_string(upload.size) + " bytes, got " + std::to_string(actual_size) +
                       "; the upload was deleted");
  }
  const fs::path part = uploads_.part_path(upload_id);
  const std::string actual_sha256 = sha256_file(part);
  if (actual_sha256 != sha256) {
    discard_upload(upload_id);
    throw Sha256Mismatch("upload " + upload_id + " (" + upload.name + "): expected SHA-256 " +
                         sha256 + ", got " + actual_sha256 + "; the upload was deleted");
  }
  blobs_.adopt(part, sha256);
  write([&](Database& db) {
    auto insert =
        db.cached("INSERT OR IGNORE INTO blobs (sha256, size, created_at_ms) VALUES (?1, ?2, ?3)");
    insert->bind_text(1, sha256).bind_int64(2, upload.size).bind_int64(3, clock_()).run();
    auto remove = db.cached("DELETE FROM uploads WHERE id = ?1");
    remove->bind_text(1, upload_id).run();
    note_blob_ref(db, upload.project, sha256);
  });
  return sha256;
}

void SqliteStore::delete_upload(const std::string& upload_id) {
  std::lock_guard<std::mutex> lock(upload_lock(upload_id));
  write([&](Database& db) {
    auto statement = db.cached("DELETE FROM uploads WHERE id = ?1");
    statement->bind_text(1, upload_id).run();
    if (db.changes() != 1) throw upload_not_found(upload_id);
  });
  uploads_.remove(upload_id);
}

// --- blobs ---

bool SqliteStore::has_blob(const std::string& sha256) {
  if (!proto::is_sha256_hex(sha256)) return false;
  return read([&](Database& db) { return find_blob_size(db, sha256).has_value(); });
}

int64_t SqliteStore::blob_size(const std::string& sha256) {
  require_sha256(sha256, "blob");
  auto size = read([&](Database& db) { return find_blob_size(db, sha256); });
  if (!size) throw NotFound("blob " + sha256 + " not found");
  return *size;
}

fs::path SqliteStore::blob_path(const std::string& sha256) {
  blob_size(sha256);  // NotFound / Invalid
  return blobs_.path_of(sha256);
}

std::string SqliteStore::put_blob(const std::string& bytes) {
  const std::string sha256 = blobs_.put(bytes);
  write([&](Database& db) {
    auto statement =
        db.cached("INSERT OR IGNORE INTO blobs (sha256, size, created_at_ms) VALUES (?1, ?2, ?3)");
    statement->bind_text(1, sha256)
        .bind_int64(2, static_cast<int64_t>(bytes.size()))
        .bind_int64(3, clock_())
        .run();
  });
  return sha256;
}

// --- missions ---

proto::Mission SqliteStore::create_mission(const proto::MissionRequest& request) {
  require_mission_request(request);
  proto::Mission mission;
  mission.id = new_id(kMissionPrefix);
  mission.name = request.name;
  mission.bundle_blob = request.bundle_blob;
  mission.cad_blob = request.cad_blob;
  mission.cad_name = request.cad_name;
  mission.created_at_ms = clock_();
  write([&](Database& db) {
    mission.project = project_of_request(db, request.project);
    if (!find_blob_size(db, mission.bundle_blob))
      throw NotFound("bundle_blob: blob " + mission.bundle_blob + " not found (upload it first)");
    if (!mission.cad_blob.empty() && !find_blob_size(db, mission.cad_blob))
      throw NotFound("cad_blob: blob " + mission.cad_blob + " not found (upload it first)");
    auto statement = db.cached(
        "INSERT INTO missions (id, name, bundle_blob, cad_blob, cad_name, created_at_ms, "
        "project) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
    statement->bind_text(1, mission.id)
        .bind_text(2, mission.name)
        .bind_text(3, mission.bundle_blob)
        .bind_text_or_null(4, mission.cad_blob)
        .bind_text(5, mission.cad_name)
        .bind_int64(6, mission.created_at_ms)
        .bind_text(7, mission.project)
        .run();
    note_blob_ref(db, mission.project, mission.bundle_blob);
    if (!mission.cad_blob.empty()) note_blob_ref(db, mission.project, mission.cad_blob);
  });
  return mission;
}

proto::Mission SqliteStore::get_mission(const std::string& mission_id) {
  auto mission = read([&](Database& db) { return find_mission(db, mission_id); });
  if (!mission) throw NotFound("mission " + mission_id + " not found");
  return *mission;
}

std::vector<proto::Mission> SqliteStore::list_missions(const std::string& name_prefix,
                                                       const std::string& project) {
  return read([&](Database& db) { return query_missions(db, name_prefix, project); });
}

// --- tokens ---

namespace {

constexpr const char* kTokenSelect =
    "SELECT id, label, role, project, created_at_ms, expires_at_ms, revoked_at_ms "
    "FROM api_tokens";

proto::TokenInfo read_token(const Statement& row) {
  proto::TokenInfo token;
  token.id = row.column_text(0);
  token.label = row.column_text(1);
  token.role = proto::role_from_string(row.column_text(2), "api_tokens.role of " + token.id);
  token.project = row.column_text(3);
  token.created_at_ms = row.column_int64(4);
  token.expires_at_ms = row.column_int64(5);
  token.revoked_at_ms = row.column_int64(6);
  return token;
}

void insert_project(Database& db, const std::string& name, int64_t now_ms) {
  auto statement = db.cached(
      "INSERT INTO projects (name, created_at_ms) VALUES (?1, ?2) ON CONFLICT (name) DO NOTHING");
  statement->bind_text(1, name).bind_int64(2, now_ms).run();
}

}  // namespace

std::string SqliteStore::project_of_request(Database& db, const std::string& project) {
  if (project.empty()) return proto::kDefaultProject;
  require_project_name(project, "project");
  insert_project(db, project, clock_());
  return project;
}

proto::TokenInfo SqliteStore::add_token(const std::string& token, const TokenSpec& spec) {
  require_token_spec(token, spec);
  const std::string hash = sha256_bytes(token);  // the clear token is never stored
  return write([&](Database& db) {
    const int64_t now_ms = clock_();
    if (spec.project != proto::kAllProjects) insert_project(db, spec.project, now_ms);
    auto insert = db.cached(
        "INSERT INTO api_tokens (token_sha256, label, created_at_ms, id, role, project, "
        "expires_at_ms) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7) "
        "ON CONFLICT (token_sha256) DO NOTHING");
    insert->bind_text(1, hash)
        .bind_text(2, spec.label)
        .bind_int64(3, now_ms)
        .bind_text(4, new_id(kTokenPrefix))
        .bind_text(5, proto::to_string(spec.role))
        .bind_text(6, spec.project)
        .bind_int64(7, spec.expires_at_ms)
        .run();
    static const std::string sql = std::string(kTokenSelect) + " WHERE token_sha256 = ?1";
    auto select = db.cached(sql);
    select->bind_text(1, hash);
    select->step();
    return read_token(*select);
  });
}

std::optional<proto::TokenInfo> SqliteStore::check_token(const std::string& token) {
  if (token.empty()) return std::nullopt;
  const std::string hash = sha256_bytes(token);
  auto info = read([&](Database& db) -> std::optional<proto::TokenInfo> {
    static const std::string sql = std::string(kTokenSelect) + " WHERE token_sha256 = ?1";
    auto statement = db.cached(sql);
    statement->bind_text(1, hash);
    if (!statement->step()) return std::nullopt;
    return read_token(*statement);
  });
  if (!info || info->revoked_at_ms != 0) return std::nullopt;
  if (info->expires_at_ms != 0 && clock_() >= info->expires_at_ms) return std::nullopt;
  return info;
}

std::vector<proto::TokenInfo> SqliteStore::list_tokens() {
  return read([&](Database& db) {
    static const std::string sql = std::string(kTokenSelect) + " ORDER BY created_at_ms, rowid";
    auto statement = db.cached(sql);
    std::vector<proto::TokenInfo> tokens;
    while (statement->step()) tokens.push_back(read_token(*statement));
    return tokens;
  });
}

proto::TokenInfo SqliteStore::revoke_token(const std::string& token_id) {
  return write([&](Database& db) {
    auto update =
        db.cached("UPDATE api_tokens SET revoked_at_ms = ?2 WHERE id = ?1 AND revoked_at_ms = 0");
    update->bind_text(1, token_id).bind_int64(2, clock_()).run();
    static const std::string sql = std::string(kTokenSelect) + " WHERE id = ?1";
    auto select = db.cached(sql);
    select->bind_text(1, token_id);
    if (!select->step()) throw NotFound("token " + token_id + " not found");
    return read_token(*select);
  });
}

int64_t SqliteStore::token_count() {
  return read([&](Database& db) {
    auto statement = db.cached("SELECT COUNT(*) FROM api_tokens");
    statement->step();
    return statement->column_int64(0);
  });
}

// --- projects ---

std::vector<proto::Project> SqliteStore::list_projects() {
  return read([&](Database& db) {
    auto statement =
        db.cached("SELECT name, created_at_ms, quota_bytes FROM projects ORDER BY name");
    std::vector<proto::Project> projects;
    while (statement->step())
      projects.push_back(
          {statement->column_text(0), statement->column_int64(1), statement->column_int64(2)});
    return projects;
  });
}

proto::Project SqliteStore::ensure_project(const std::string& name) {
  require_project_name(name, "project");
  return write([&](Database& db) {
    insert_project(db, name, clock_());
    auto statement =
        db.cached("SELECT name, created_at_ms, quota_bytes FROM projects WHERE name = ?1");
    statement->bind_text(1, name);
    statement->step();
    return proto::Project{statement->column_text(0), statement->column_int64(1),
                          statement->column_int64(2)};
  });
}

proto::Project SqliteStore::set_project_quota(const std::string& name, int64_t quota_bytes) {
  require_project_name(name, "project");
  if (quota_bytes < 0) throw Invalid("quota_bytes: expected bytes >= 0 (0 = no quota)");
  write([&](Database& db) {
    insert_project(db, name, clock_());
    auto statement = db.cached("UPDATE projects SET quota_bytes = ?2 WHERE name = ?1");
    statement->bind_text(1, name).bind_int64(2, quota_bytes).run();
  });
  return ensure_project(name);
}

int64_t SqliteStore::project_usage(const std::string& name) {
  return read([&](Database& db) {
    auto statement = db.cached(
        "SELECT (SELECT COALESCE(SUM(b.size), 0) FROM blob_refs r "
        "        JOIN blobs b ON b.sha256 = r.sha256 WHERE r.project = ?1) + "
        "       (SELECT COALESCE(SUM(size), 0) FROM uploads WHERE project = ?1)");
    statement->bind_text(1, name);
    statement->step();
    return statement->column_int64(0);
  });
}

bool SqliteStore::project_has_blob(const std::string& name, const std::string& sha256) {
  return read([&](Database& db) {
    auto statement = db.cached("SELECT 1 FROM blob_refs WHERE project = ?1 AND sha256 = ?2");
    statement->bind_text(1, name).bind_text(2, sha256);
    return statement->step();
  });
}

void SqliteStore::note_blob_ref(Database& db, const std::string& project,
                                const std::string& sha256) {
  auto statement =
      db.cached("INSERT OR IGNORE INTO blob_refs (project, sha256) VALUES (?1, ?2)");
  statement->bind_text(1, project).bind_text(2, sha256).run();
}

// --- live changes ---

std::unique_ptr<Subscription> SqliteStore::subscribe(ChangeListener listener) {
  return changes_.subscribe(std::move(listener));
}

void SqliteStore::note_job(Database& db, const std::string& job_id) {
  auto statement = db.cached("SELECT project, state FROM jobs WHERE id = ?1");
  statement->bind_text(1, job_id);
  if (!statement->step()) return;
  Change change;
  change.kind = Change::Kind::kJob;
  change.job_id = job_id;
  change.project = statement->column_text(0);
  change.state = proto::job_state_from_string(statement->column_text(1));
  pending_changes_.push_back(std::move(change));
}

void SqliteStore::note_log(Database& db, const std::string& job_id) {
  auto statement = db.cached("SELECT project FROM jobs WHERE id = ?1");
  statement->bind_text(1, job_id);
  if (!statement->step()) return;
  Change change;
  change.kind = Change::Kind::kLog;
  change.job_id = job_id;
  change.project = statement->column_text(0);
  pending_changes_.push_back(std::move(change));
}

void SqliteStore::note_worker(Database& db, const std::string& worker, const std::string& job_id,
                              int64_t now_ms) {
  if (worker.empty()) return;
  auto statement = db.cached(
      "INSERT INTO workers (id, job_id, last_seen_ms) VALUES (?1, ?2, ?3) "
      "ON CONFLICT (id) DO UPDATE SET job_id = excluded.job_id, "
      "last_seen_ms = excluded.last_seen_ms");
  statement->bind_text(1, worker).bind_text(2, job_id).bind_int64(3, now_ms).run();
}

// --- metrics ---

Metrics SqliteStore::metrics() {
  return read([&](Database& db) {
    Metrics metrics;
    Transaction snapshot(db, Transaction::Mode::kDeferred);  // all counts from one state
    {
      auto statement = db.cached("SELECT state, COUNT(*) FROM jobs GROUP BY state");
      while (statement->step())
        metrics.jobs_by_state[static_cast<int>(
            proto::job_state_from_string(statement->column_text(0)))] = statement->column_int64(1);
    }
    {
      auto statement = db.cached("SELECT COUNT(*) FROM missions");
      statement->step();
      metrics.missions = statement->column_int64(0);
    }
    {
      auto statement = db.cached("SELECT COUNT(*), COALESCE(SUM(size), 0) FROM blobs");
      statement->step();
      metrics.blobs = statement->column_int64(0);
      metrics.blob_bytes = statement->column_int64(1);
    }
    {
      auto statement = db.cached("SELECT COUNT(*) FROM uploads");
      statement->step();
      metrics.uploads_open = statement->column_int64(0);
    }
    snapshot.commit();
    return metrics;
  });
}

}  // namespace keel::storage
