// PgStore: construction and recovery, uploads, blobs, missions, tokens, projects, the
// change feed and metrics. Jobs and the worker protocol are in pg_store_jobs.cc, batches and
// the queue summary in pg_store_batches.cc.
#include "storage/pg_store.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <system_error>

#include "storage/ids.h"
#include "storage/open_store.h"
#include "storage/pg_migrations.h"
#include "storage/pg_queries.h"
#include "core/sha256.h"
#include "storage/store_rules.h"

namespace keel::storage {

namespace fs = std::filesystem;

namespace {

bool older_than(const fs::path& file, int64_t age_s) {
  std::error_code error;
  const auto written = fs::last_write_time(file, error);
  if (error) return false;
  return fs::file_time_type::clock::now() - written > std::chrono::seconds(age_s);
}

proto::TokenInfo read_token(const pqxx::row& row) {
  proto::TokenInfo token;
  token.id = row[0].as<std::string>();
  token.label = row[1].as<std::string>();
  token.role = proto::role_from_string(row[2].as<std::string>(), "api_tokens.role of " + token.id);
  token.project = row[3].as<std::string>();
  token.created_at_ms = row[4].as<int64_t>();
  token.expires_at_ms = row[5].as<int64_t>();
  token.revoked_at_ms = row[6].as<int64_t>();
  return token;
}

constexpr const char* kTokenSelect =
    "SELECT id, label, role, project, created_at_ms, expires_at_ms, revoked_at_ms "
    "FROM api_tokens";

void insert_project(PgTx& tx, const std::string& name, int64_t now_ms) {
  tx.exec(
      "INSERT INTO projects (name, created_at_ms) VALUES ($1, $2) "
      "ON CONFLICT (name) DO NOTHING",
      name, now_ms);
}

}  // namespace

PgStore::PgStore(const PgStoreOptions& options, Clock clock)
    : options_(options),
      clock_(clock ? std::move(clock) : Clock(system_clock_ms)),
      blobs_(options.blob_dir / "blobs", options.blob_dir / "tmp"),
      uploads_(options.blob_dir / "uploads"),
      pool_(with_connect_timeout(options.database_url, options.connect_timeout_s),
            options.max_connections),
      origin_(random_hex(8)) {
  apply_pg_migrations(pool_, pg_migrations());
  recover_uploads();
  if (options_.listen) {
    notifier_ = std::make_unique<PgNotifier>(pool_.url(), origin_);
    PgListenerOptions listen;
    listen.database_url = pool_.url();
    listen.origin = origin_;
    listen.deliver = [this](const std::vector<Change>& changes) { changes_.publish(changes); };
    // Notifications sent while the link was down are lost: every project's listeners are
    // told to re-read (a job_id "" change, as for a batch).
    listen.on_reconnect = [this] {
      try {
        Changes reload;
        for (const proto::Project& project : list_projects()) {
          Change change;
          change.project = project.name;
          change.state = proto::JobState::kQueued;
          reload.push_back(change);
        }
        changes_.publish(reload);
      } catch (const std::exception& error) {
        spdlog::warn("change feed: after reconnecting: {}", error.what());
      }
    };
    listener_ = std::make_unique<PgListener>(std::move(listen));
    // The pool just connected, so the listener's connection normally follows within
    // milliseconds; if it does not, the store still works (the long poll's fallback tick).
    const auto wait = std::chrono::milliseconds(1000 * std::max(1, options_.connect_timeout_s));
    if (!listener_->wait_listening(wait))
      spdlog::warn(
          "change feed: not listening yet after {} ms; changes of other replicas "
          "reach this one by the fallback poll until it is",
          wait.count());
  }
}

PgStore::~PgStore() {
  listener_.reset();
  notifier_.reset();
}

// --- change feed ---

void PgStore::committed(const Changes& changes) {
  if (changes.empty()) return;
  changes_.publish(changes);
  if (notifier_) notifier_->send(changes);
}

void PgStore::note_job(PgTx& tx, Changes& changes, const std::string& job_id) {
  const pqxx::result rows = tx.exec("SELECT project, state FROM jobs WHERE id = $1", job_id);
  if (rows.empty()) return;
  Change change;
  change.kind = Change::Kind::kJob;
  change.job_id = job_id;
  change.project = rows[0][0].as<std::string>();
  change.state = proto::job_state_from_string(rows[0][1].as<std::string>());
  changes.push_back(std::move(change));
}

void PgStore::note_log(PgTx& tx, Changes& changes, const std::string& job_id) {
  const pqxx::result rows = tx.exec("SELECT project FROM jobs WHERE id = $1", job_id);
  if (rows.empty()) return;
  Change change;
  change.kind = Change::Kind::kLog;
  change.job_id = job_id;
  change.project = rows[0][0].as<std::string>();
  changes.push_back(std::move(change));
}

std::unique_ptr<Subscription> PgStore::subscribe(ChangeListener listener) {
  return changes_.subscribe(std::move(listener));
}

// --- uploads ---

void PgStore::recover_uploads() {
  // Rows locked by another replica are being written right now: skip them.
  read([&](PgTx& tx) {
    const pqxx::result rows =
        tx.exec("SELECT id, committed FROM uploads ORDER BY id FOR UPDATE SKIP LOCKED");
    for (const auto& row : rows) {
      const std::string id = row[0].as<std::string>();
      const int64_t committed = row[1].as<int64_t>();
      // A chunk written and fsynced whose offset never committed (killed in between)
      // leaves the file longer than the committed offset: cut it so a resume is exact.
      const int64_t kept = uploads_.truncate_to(id, committed);
      if (kept < committed) tx.exec("UPDATE uploads SET committed = $2 WHERE id = $1", id, kept);
    }
  });
  // Rows are committed before their part file is made and deleted before it is removed, so
  // a part file without a row is left over (a deletion or completion cut short).
  for (const std::string& id : uploads_.part_ids()) {
    const bool known = read([&](PgTx& tx) { return pg_find_upload(tx, id).has_value(); });
    if (!known) uploads_.remove(id);
  }
  // Temp files may be another replica's blob being written: only old ones are left over.
  for (const auto& entry : fs::directory_iterator(blobs_.tmp_dir())) {
    std::error_code ignored;
    if (older_than(entry.path(), options_.stale_file_age_s)) fs::remove_all(entry.path(), ignored);
  }
}

proto::Upload PgStore::create_upload(const proto::UploadRequest& request) {
  rules::require_upload_size(request.size);
  proto::Upload upload;
  upload.id = new_id(kUploadPrefix);
  upload.name = request.name;
  upload.size = request.size;
  write([&](PgTx& tx, Changes&) {
    upload.project = project_of_request(tx, request.project);
    tx.exec(
        "INSERT INTO uploads (id, name, size, committed, created_at_ms, project) "
        "VALUES ($1, $2, $3, 0, $4, $5)",
        upload.id, upload.name, upload.size, clock_(), upload.project);
  });
  try {
    uploads_.create(upload.id);  // after the row: a part file without a row is an orphan
  } catch (...) {
    discard_upload(upload.id);
    throw;
  }
  return upload;
}

proto::Upload PgStore::get_upload(const std::string& upload_id) {
  auto upload = read([&](PgTx& tx) { return pg_find_upload(tx, upload_id); });
  if (!upload) throw rules::upload_not_found(upload_id);
  return *upload;
}

proto::Upload PgStore::append_upload(const std::string& upload_id, int64_t offset, const char* data,
                                     size_t size) {
  // The row lock is held while the chunk is cut, written and fsynced: another replica's
  // append of the same upload waits, and a crash anywhere rolls the offset back.
  std::exception_ptr refused;
  proto::Upload upload = write([&](PgTx& tx, Changes&) {
    static const std::string sql =
        "SELECT id, name, size, committed, project FROM uploads WHERE id = $1 FOR UPDATE";
    const pqxx::result rows = tx.exec(sql, upload_id);
    if (rows.empty()) throw rules::upload_not_found(upload_id);
    proto::Upload upload;
    upload.id = rows[0][0].as<std::string>();
    upload.name = rows[0][1].as<std::string>();
    upload.size = rows[0][2].as<int64_t>();
    upload.offset = rows[0][3].as<int64_t>();
    upload.project = rows[0][4].as<std::string>();
    if (offset != upload.offset)
      throw OffsetMismatch("upload " + upload_id + ": chunk starts at byte " +
                               std::to_string(offset) + " but " + std::to_string(upload.offset) +
                               " bytes are committed; resume from byte " +
                               std::to_string(upload.offset),
                           upload.offset);
    if (size > static_cast<uint64_t>(upload.size - upload.offset))
      throw Invalid("upload " + upload_id + ": chunk of " + std::to_string(size) +
                    " bytes at byte " + std::to_string(offset) +
                    " ends beyond the announced size of " + std::to_string(upload.size) + " bytes");
    const int64_t kept = uploads_.truncate_to(upload_id, offset);
    if (kept < offset) {
      // Committed bytes vanished from the part file (damaged or removed by hand): move the
      // offset back (committed) so the client resumes from what is really there.
      tx.exec("UPDATE uploads SET committed = $2 WHERE id = $1", upload_id, kept);
      refused = std::make_exception_ptr(OffsetMismatch(
          "upload " + upload_id + ": the part file holds only " + std::to_string(kept) + " of " +
              std::to_string(offset) + " committed bytes; resume from byte " + std::to_string(kept),
          kept));
      return upload;
    }
    uploads_.write_chunk(upload_id, offset, data, size);
    upload.offset = offset + static_cast<int64_t>(size);
    tx.exec("UPDATE uploads SET committed = $2 WHERE id = $1", upload_id, upload.offset);
    return upload;
  });
  if (refused) std::rethrow_exception(refused);
  return upload;
}

void PgStore::discard_upload(const std::string& upload_id) {
  write([&](PgTx& tx, Changes&) { tx.exec("DELETE FROM uploads WHERE id = $1", upload_id); });
  uploads_.remove(upload_id);
}

std::string PgStore::complete_upload(const std::string& upload_id, const std::string& sha256) {
  rules::require_sha256(sha256, "sha256");
  std::exception_ptr refused;
  write([&](PgTx& tx, Changes&) {
    const pqxx::result rows = tx.exec(
        "SELECT name, size, committed, project FROM uploads WHERE id = $1 FOR UPDATE", upload_id);
    if (rows.empty()) throw rules::upload_not_found(upload_id);
    const std::string name = rows[0][0].as<std::string>();
    const int64_t size = rows[0][1].as<int64_t>();
    const int64_t committed = rows[0][2].as<int64_t>();
    const int64_t actual_size = uploads_.truncate_to(upload_id, committed);
    // A wrong size or hash deletes the upload: the row in this transaction, the file after.
    if (actual_size != size) {
      tx.exec("DELETE FROM uploads WHERE id = $1", upload_id);
      refused = std::make_exception_ptr(
          SizeMismatch("upload " + upload_id + " (" + name + "): expected " + std::to_string(size) +
                       " bytes, got " + std::to_string(actual_size) + "; the upload was deleted"));
      return;
    }
    const fs::path part = uploads_.part_path(upload_id);
    const std::string actual_sha256 = sha256_file(part);
    if (actual_sha256 != sha256) {
      tx.exec("DELETE FROM uploads WHERE id = $1", upload_id);
      refused = std::make_exception_ptr(Sha256Mismatch("upload " + upload_id + " (" + name +
                                                       "): expected SHA-256 " + sha256 + ", got " +
                                                       actual_sha256 + "; the upload was deleted"));
      return;
    }
    blobs_.adopt(part, sha256);
    tx.exec(
        "INSERT INTO blobs (sha256, size, created_at_ms) VALUES ($1, $2, $3) "
        "ON CONFLICT (sha256) DO NOTHING",
        sha256, size, clock_());
    tx.exec("DELETE FROM uploads WHERE id = $1", upload_id);
    pg_note_blob_ref(tx, rows[0][3].as<std::string>(), sha256);
  });
  if (refused) {
    uploads_.remove(upload_id);
    std::rethrow_exception(refused);
  }
  return sha256;
}

void PgStore::delete_upload(const std::string& upload_id) {
  write([&](PgTx& tx, Changes&) {
    if (tx.exec("DELETE FROM uploads WHERE id = $1 RETURNING id", upload_id).empty())
      throw rules::upload_not_found(upload_id);
  });
  uploads_.remove(upload_id);
}

// --- blobs ---

bool PgStore::has_blob(const std::string& sha256) {
  if (!proto::is_sha256_hex(sha256)) return false;
  return read([&](PgTx& tx) { return pg_find_blob_size(tx, sha256).has_value(); });
}

int64_t PgStore::blob_size(const std::string& sha256) {
  rules::require_sha256(sha256, "blob");
  auto size = read([&](PgTx& tx) { return pg_find_blob_size(tx, sha256); });
  if (!size) throw NotFound("blob " + sha256 + " not found");
  return *size;
}

fs::path PgStore::blob_path(const std::string& sha256) {
  blob_size(sha256);  // NotFound / Invalid
  return blobs_.path_of(sha256);
}

std::string PgStore::put_blob(const std::string& bytes) {
  const std::string sha256 = blobs_.put(bytes);
  write([&](PgTx& tx, Changes&) {
    tx.exec(
        "INSERT INTO blobs (sha256, size, created_at_ms) VALUES ($1, $2, $3) "
        "ON CONFLICT (sha256) DO NOTHING",
        sha256, static_cast<int64_t>(bytes.size()), clock_());
  });
  return sha256;
}

// --- missions ---

proto::Mission PgStore::create_mission(const proto::MissionRequest& request) {
  rules::require_mission_request(request);
  proto::Mission mission;
  mission.id = new_id(kMissionPrefix);
  mission.name = request.name;
  mission.bundle_blob = request.bundle_blob;
  mission.cad_blob = request.cad_blob;
  mission.cad_name = request.cad_name;
  mission.created_at_ms = clock_();
  write([&](PgTx& tx, Changes&) {
    mission.project = project_of_request(tx, request.project);
    if (!pg_find_blob_size(tx, mission.bundle_blob))
      throw NotFound("bundle_blob: blob " + mission.bundle_blob + " not found (upload it first)");
    if (!mission.cad_blob.empty() && !pg_find_blob_size(tx, mission.cad_blob))
      throw NotFound("cad_blob: blob " + mission.cad_blob + " not found (upload it first)");
    tx.exec(
        "INSERT INTO missions (id, name, bundle_blob, cad_blob, cad_name, created_at_ms, "
        "project) VALUES ($1, $2, $3, NULLIF($4, ''), $5, $6, $7)",
        mission.id, mission.name, mission.bundle_blob, mission.cad_blob, mission.cad_name,
        mission.created_at_ms, mission.project);
    pg_note_blob_ref(tx, mission.project, mission.bundle_blob);
    if (!mission.cad_blob.empty()) pg_note_blob_ref(tx, mission.project, mission.cad_blob);
  });
  return mission;
}

proto::Mission PgStore::get_mission(const std::string& mission_id) {
  auto mission = read([&](PgTx& tx) { return pg_find_mission(tx, mission_id); });
  if (!mission) throw rules::mission_not_found(mission_id);
  return *mission;
}

std::vector<proto::Mission> PgStore::list_missions(const std::string& name_prefix,
                                                   const std::string& project) {
  return read([&](PgTx& tx) { return pg_query_missions(tx, name_prefix, project); });
}

// --- tokens and projects ---

std::string PgStore::project_of_request(PgTx& tx, const std::string& project) {
  if (project.empty()) return proto::kDefaultProject;
  rules::require_project_name(project, "project");
  insert_project(tx, project, clock_());
  return project;
}

proto::TokenInfo PgStore::add_token(const std::string& token, const TokenSpec& spec) {
  rules::require_token_spec(token, spec);
  const std::string hash = sha256_bytes(token);  // the clear token is never stored
  return write([&](PgTx& tx, Changes&) {
    const int64_t now_ms = clock_();
    if (spec.project != proto::kAllProjects) insert_project(tx, spec.project, now_ms);
    tx.exec(
        "INSERT INTO api_tokens (token_sha256, label, created_at_ms, id, role, project, "
        "expires_at_ms) VALUES ($1, $2, $3, $4, $5, $6, $7) "
        "ON CONFLICT (token_sha256) DO NOTHING",
        hash, spec.label, now_ms, new_id(kTokenPrefix), proto::to_string(spec.role), spec.project,
        spec.expires_at_ms);
    static const std::string sql = std::string(kTokenSelect) + " WHERE token_sha256 = $1";
    return read_token(tx.exec(sql, hash)[0]);
  });
}

std::optional<proto::TokenInfo> PgStore::check_token(const std::string& token) {
  if (token.empty()) return std::nullopt;
  const std::string hash = sha256_bytes(token);
  auto info = read([&](PgTx& tx) -> std::optional<proto::TokenInfo> {
    static const std::string sql = std::string(kTokenSelect) + " WHERE token_sha256 = $1";
    const pqxx::result rows = tx.exec(sql, hash);
    if (rows.empty()) return std::nullopt;
    return read_token(rows[0]);
  });
  if (!info || info->revoked_at_ms != 0) return std::nullopt;
  if (info->expires_at_ms != 0 && clock_() >= info->expires_at_ms) return std::nullopt;
  return info;
}

std::vector<proto::TokenInfo> PgStore::list_tokens() {
  return read([&](PgTx& tx) {
    static const std::string sql = std::string(kTokenSelect) + " ORDER BY created_at_ms, seq";
    std::vector<proto::TokenInfo> tokens;
    for (const auto& row : tx.exec(sql)) tokens.push_back(read_token(row));
    return tokens;
  });
}

proto::TokenInfo PgStore::revoke_token(const std::string& token_id) {
  return write([&](PgTx& tx, Changes&) {
    tx.exec("UPDATE api_tokens SET revoked_at_ms = $2 WHERE id = $1 AND revoked_at_ms = 0",
            token_id, clock_());
    static const std::string sql = std::string(kTokenSelect) + " WHERE id = $1";
    const pqxx::result rows = tx.exec(sql, token_id);
    if (rows.empty()) throw NotFound("token " + token_id + " not found");
    return read_token(rows[0]);
  });
}

int64_t PgStore::token_count() {
  return read(
      [&](PgTx& tx) { return tx.exec("SELECT COUNT(*) FROM api_tokens")[0][0].as<int64_t>(); });
}

std::vector<proto::Project> PgStore::list_projects() {
  return read([&](PgTx& tx) {
    std::vector<proto::Project> projects;
    for (const auto& row :
         tx.exec("SELECT name, created_at_ms, quota_bytes FROM projects ORDER BY name"))
      projects.push_back({row[0].as<std::string>(), row[1].as<int64_t>(), row[2].as<int64_t>()});
    return projects;
  });
}

proto::Project PgStore::ensure_project(const std::string& name) {
  rules::require_project_name(name, "project");
  return write([&](PgTx& tx, Changes&) {
    insert_project(tx, name, clock_());
    const pqxx::row row =
        tx.exec("SELECT name, created_at_ms, quota_bytes FROM projects WHERE name = $1", name)[0];
    return proto::Project{row[0].as<std::string>(), row[1].as<int64_t>(), row[2].as<int64_t>()};
  });
}

proto::Project PgStore::set_project_quota(const std::string& name, int64_t quota_bytes) {
  rules::require_project_name(name, "project");
  if (quota_bytes < 0) throw Invalid("quota_bytes: expected bytes >= 0 (0 = no quota)");
  return write([&](PgTx& tx, Changes&) {
    insert_project(tx, name, clock_());
    const pqxx::row row = tx.exec(
        "UPDATE projects SET quota_bytes = $2 WHERE name = $1 "
        "RETURNING name, created_at_ms, quota_bytes",
        name, quota_bytes)[0];
    return proto::Project{row[0].as<std::string>(), row[1].as<int64_t>(), row[2].as<int64_t>()};
  });
}

int64_t PgStore::project_usage(const std::string& name) {
  return read([&](PgTx& tx) {
    return tx
        .exec(
            "SELECT (SELECT COALESCE(SUM(b.size), 0) FROM blob_refs r "
            "        JOIN blobs b ON b.sha256 = r.sha256 WHERE r.project = $1) + "
            "       (SELECT COALESCE(SUM(size), 0) FROM uploads WHERE project = $1)",
            name)[0][0]
        .as<int64_t>();
  });
}

bool PgStore::project_has_blob(const std::string& name, const std::string& sha256) {
  return read([&](PgTx& tx) {
    return !tx.exec("SELECT 1 FROM blob_refs WHERE project = $1 AND sha256 = $2", name, sha256)
                .empty();
  });
}

// --- metrics ---

Metrics PgStore::metrics() {
  return read([&](PgTx& tx) {
    Metrics metrics;
    // One statement: every count from one snapshot.
    const pqxx::result rows = tx.exec(
        "SELECT 'job:' || state, COUNT(*), 0 FROM jobs GROUP BY state "
        "UNION ALL SELECT 'missions', COUNT(*), 0 FROM missions "
        "UNION ALL SELECT 'blobs', COUNT(*), COALESCE(SUM(size), 0) FROM blobs "
        "UNION ALL SELECT 'uploads', COUNT(*), 0 FROM uploads");
    for (const auto& row : rows) {
      const std::string what = row[0].as<std::string>();
      const int64_t count = row[1].as<int64_t>();
      if (what.rfind("job:", 0) == 0)
        metrics.jobs_by_state[static_cast<int>(proto::job_state_from_string(what.substr(4)))] =
            count;
      else if (what == "missions")
        metrics.missions = count;
      else if (what == "blobs") {
        metrics.blobs = count;
        metrics.blob_bytes = row[2].as<int64_t>();
      } else if (what == "uploads")
        metrics.uploads_open = count;
    }
    return metrics;
  });
}

}  // namespace keel::storage
