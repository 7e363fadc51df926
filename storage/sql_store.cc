// SqlStore: opening and recovery, the change feed, uploads, blobs, missions, tokens,
// projects and metrics. Jobs and the worker protocol are in sql_store_jobs.cc, batches and
// the queue summary in sql_store_batches.cc.
#include "storage/sql_store.h"

#include <chrono>
#include <functional>
#include <system_error>

#include "storage/ids.h"
#include "core/sha256.h"
#include "storage/sql_queries.h"

namespace keel::storage {

namespace fs = std::filesystem;
namespace {

bool older_than(const fs::path& file, int64_t age_s) {
  std::error_code error;
  const auto written = fs::last_write_time(file, error);
  if (error) return false;
  return fs::file_time_type::clock::now() - written > std::chrono::seconds(age_s);
}

const std::string kTokenSelect =
    "SELECT id, label, role, project, created_at_ms, expires_at_ms, revoked_at_ms "
    "FROM api_tokens";

proto::TokenInfo read_token(const SqlRow& row) {
  return {row.text(0),
          row.text(1),
          proto::role_from_string(row.text(2), "api_tokens.role of " + row.text(0)),
          row.text(3),
          row.int64(4),
          row.int64(5),
          row.int64(6)};
}

const std::string kProjectSelect = "SELECT name, created_at_ms, quota_bytes FROM projects";

proto::Project read_project(const SqlRow& row) { return {row.text(0), row.int64(1), row.int64(2)}; }

void insert_project(SqlTx& tx, const std::string& name, int64_t now_ms) {
  tx.exec(
      "INSERT INTO projects (name, created_at_ms) VALUES (?1, ?2) ON CONFLICT (name) DO NOTHING",
      {name, now_ms});
}

NotFound upload_not_found(const std::string& upload_id) {
  return NotFound("upload " + upload_id + " not found");
}

void require_project_name(const std::string& name, const std::string& field) {
  if (!proto::is_project_name(name))
    throw Invalid(field + ": project name '" + name +
                  "' must be 1..64 characters of a-z, 0-9, '.', '_' or '-', starting with a "
                  "letter or digit");
}

void insert_blob(SqlTx& tx, const std::string& sha256, int64_t size, int64_t now_ms) {
  tx.exec(
      "INSERT INTO blobs (sha256, size, created_at_ms) VALUES (?1, ?2, ?3) "
      "ON CONFLICT (sha256) DO NOTHING",
      {sha256, size, now_ms});
}

}  // namespace

int64_t system_clock_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(system_clock::now().time_since_epoch()).count();
}

void note_blob_ref(SqlTx& tx, const std::string& project, const std::string& sha256) {
  tx.exec("INSERT INTO blob_refs (project, sha256) VALUES (?1, ?2) ON CONFLICT DO NOTHING",
          {project, sha256});
}

SqlStore::SqlStore(std::unique_ptr<Sql> sql, const StoreFiles& files, Clock clock)
    : clock_(clock ? std::move(clock) : Clock(system_clock_ms)),
      blobs_(files.dir / "blobs", files.dir / "tmp"),
      uploads_(files.dir / "uploads"),
      sql_(std::move(sql)) {
  sql_->on_change([this](const std::vector<Change>& changes) { changes_.publish(changes); });
  if (files.recover) recover_uploads(files.stale_file_age_s);
}

// --- change feed ---

std::unique_ptr<Subscription> SqlStore::subscribe(ChangeListener listener) {
  return changes_.subscribe(std::move(listener));
}

// --- uploads ---

std::mutex& SqlStore::upload_lock(const std::string& upload_id) {
  return upload_locks_[std::hash<std::string>{}(upload_id) % upload_locks_.size()];
}

void SqlStore::recover_uploads(int64_t stale_file_age_s) {
  // Rows another replica holds are being written right now: skipped.
  write(
      [&](SqlTx& tx) {
        for (const SqlRow& row :
             tx.query("SELECT id, committed FROM uploads ORDER BY id{skip_locked}")) {
          // A chunk written and fsynced whose offset never committed (killed in between)
          // leaves the file longer than the committed offset: cut it so a resume is exact.
          const int64_t kept = uploads_.truncate_to(row.text(0), row.int64(1));
          if (kept < row.int64(1))
            tx.exec("UPDATE uploads SET committed = ?2 WHERE id = ?1", {row.text(0), kept});
        }
      },
      Sql::Mode::kFileWrite);
  // Rows are committed before their part file is made and deleted before it is removed, so
  // a part file without a row is left over (a deletion or completion cut short).
  for (const std::string& id : uploads_.part_ids())
    if (!read([&](SqlTx& tx) { return find_upload(tx, id).has_value(); })) uploads_.remove(id);
  // A temp file may be another replica's blob being written: only old ones are left over.
  for (const auto& entry : fs::directory_iterator(blobs_.tmp_dir())) {
    std::error_code ignored;
    if (stale_file_age_s <= 0 || older_than(entry.path(), stale_file_age_s))
      fs::remove_all(entry.path(), ignored);
  }
}

proto::Upload SqlStore::create_upload(const proto::UploadRequest& request) {
  if (request.size < 0)
    throw Invalid("upload size: expected >= 0 bytes, got " + std::to_string(request.size));
  proto::Upload upload;
  upload.id = new_id(kUploadPrefix);
  upload.name = request.name;
  upload.size = request.size;
  write([&](SqlTx& tx) {
    upload.project = project_of_request(tx, request.project);
    tx.exec(
        "INSERT INTO uploads (id, name, size, committed, created_at_ms, project) "
        "VALUES (?1, ?2, ?3, 0, ?4, ?5)",
        {upload.id, upload.name, upload.size, clock_(), upload.project});
  });
  try {
    uploads_.create(upload.id);  // after the row: a part file without a row is an orphan
  } catch (...) {
    discard_upload(upload.id);
    throw;
  }
  return upload;
}

proto::Upload SqlStore::get_upload(const std::string& upload_id) {
  auto upload = read([&](SqlTx& tx) { return find_upload(tx, upload_id); });
  if (!upload) throw upload_not_found(upload_id);
  return *upload;
}

proto::Upload SqlStore::append_upload(const std::string& upload_id, int64_t offset,
                                      const char* data, size_t size) {
  std::lock_guard<std::mutex> lock(upload_lock(upload_id));
  std::optional<OffsetMismatch> refused;
  proto::Upload upload = write(
      [&](SqlTx& tx) {
        refused.reset();
        auto found = find_upload(tx, upload_id, /*lock=*/true);
        if (!found) throw upload_not_found(upload_id);
        proto::Upload upload = *found;
        if (offset != upload.offset)
          throw OffsetMismatch(
              "upload " + upload_id + ": chunk starts at byte " + std::to_string(offset) + " but " +
                  std::to_string(upload.offset) + " bytes are committed; resume from byte " +
                  std::to_string(upload.offset),
              upload.offset);
        if (size > static_cast<uint64_t>(upload.size - upload.offset))
          throw Invalid("upload " + upload_id + ": chunk of " + std::to_string(size) +
                        " bytes at byte " + std::to_string(offset) +
                        " ends beyond the announced size of " + std::to_string(upload.size) +
                        " bytes");
        const int64_t kept = uploads_.truncate_to(upload_id, offset);
        if (kept < offset) {
          // Committed bytes vanished from the part file (damaged or removed by hand): move
          // the offset back (committed) so the client resumes from what is really there.
          tx.exec("UPDATE uploads SET committed = ?2 WHERE id = ?1", {upload_id, kept});
          refused.emplace("upload " + upload_id + ": the part file holds only " +
                              std::to_string(kept) + " of " + std::to_string(offset) +
                              " committed bytes; resume from byte " + std::to_string(kept),
                          kept);
          return upload;
        }
        // Durable bytes first, then the offset: a crash in between leaves extra bytes in the
        // file that the next append or open cuts, never a committed offset without its bytes.
        uploads_.write_chunk(upload_id, offset, data, size);
        upload.offset = offset + static_cast<int64_t>(size);
        if (tx.exec("UPDATE uploads SET committed = ?3 WHERE id = ?1 AND committed = ?2",
                    {upload_id, offset, upload.offset}) != 1)
          throw upload_not_found(upload_id);
        return upload;
      },
      Sql::Mode::kFileWrite);
  if (refused) throw *refused;
  return upload;
}

void SqlStore::discard_upload(const std::string& upload_id) {
  write([&](SqlTx& tx) { tx.exec("DELETE FROM uploads WHERE id = ?1", {upload_id}); });
  uploads_.remove(upload_id);
}

std::string SqlStore::complete_upload(const std::string& upload_id, const std::string& sha256) {
  require_sha256(sha256, "sha256");
  std::lock_guard<std::mutex> lock(upload_lock(upload_id));
  std::exception_ptr refused;
  write(
      [&](SqlTx& tx) {
        refused = nullptr;
        const auto upload = find_upload(tx, upload_id, /*lock=*/true);
        if (!upload) throw upload_not_found(upload_id);
        const std::string what = "upload " + upload_id + " (" + upload->name + "): expected ";
        const int64_t actual_size = uploads_.truncate_to(upload_id, upload->offset);
        // A wrong size or hash deletes the upload: the row here, the file after.
        if (actual_size != upload->size) {
          tx.exec("DELETE FROM uploads WHERE id = ?1", {upload_id});
          refused = std::make_exception_ptr(
              SizeMismatch(what + std::to_string(upload->size) + " bytes, got " +
                           std::to_string(actual_size) + "; the upload was deleted"));
          return;
        }
        const fs::path part = uploads_.part_path(upload_id);
        const std::string actual_sha256 = sha256_file(part);
        if (actual_sha256 != sha256) {
          tx.exec("DELETE FROM uploads WHERE id = ?1", {upload_id});
          refused = std::make_exception_ptr(Sha256Mismatch(
              what + "SHA-256 " + sha256 + ", got " + actual_sha256 + "; the upload was deleted"));
          return;
        }
        blobs_.adopt(part, sha256);
        // The upload's row goes last: after a crash in between, the upload is still open and
        // is sent again, and the blob file already in place is kept.
        insert_blob(tx, sha256, upload->size, clock_());
        note_blob_ref(tx, upload->project, sha256);
        tx.exec("DELETE FROM uploads WHERE id = ?1", {upload_id});
      },
      Sql::Mode::kFileWrite);
  if (refused) {
    uploads_.remove(upload_id);
    std::rethrow_exception(refused);
  }
  return sha256;
}

void SqlStore::delete_upload(const std::string& upload_id) {
  std::lock_guard<std::mutex> lock(upload_lock(upload_id));
  write([&](SqlTx& tx) {
    if (tx.exec("DELETE FROM uploads WHERE id = ?1", {upload_id}) != 1)
      throw upload_not_found(upload_id);
  });
  uploads_.remove(upload_id);
}

// --- blobs ---

bool SqlStore::has_blob(const std::string& sha256) {
  if (!proto::is_sha256_hex(sha256)) return false;
  return read([&](SqlTx& tx) { return find_blob_size(tx, sha256).has_value(); });
}

int64_t SqlStore::blob_size(const std::string& sha256) {
  require_sha256(sha256, "blob");
  auto size = read([&](SqlTx& tx) { return find_blob_size(tx, sha256); });
  if (!size) throw NotFound("blob " + sha256 + " not found");
  return *size;
}

fs::path SqlStore::blob_path(const std::string& sha256) {
  blob_size(sha256);  // NotFound / Invalid
  return blobs_.path_of(sha256);
}

std::string SqlStore::put_blob(const std::string& bytes) {
  const std::string sha256 = blobs_.put(bytes);
  write([&](SqlTx& tx) { insert_blob(tx, sha256, static_cast<int64_t>(bytes.size()), clock_()); });
  return sha256;
}

// --- missions ---

proto::Mission SqlStore::create_mission(const proto::MissionRequest& request) {
  if (request.name.empty()) throw Invalid("name: expected a non-empty mission name");
  require_sha256(request.bundle_blob, "bundle_blob");
  if (!request.cad_blob.empty()) {
    require_sha256(request.cad_blob, "cad_blob");
    if (request.cad_name.empty())
      throw Invalid("cad_name: required with cad_blob (its extension tells the mesh format)");
  } else if (!request.cad_name.empty()) {
    throw Invalid("cad_name: given without cad_blob");
  }
  proto::Mission mission;
  mission.id = new_id(kMissionPrefix);
  mission.name = request.name;
  mission.bundle_blob = request.bundle_blob;
  mission.cad_blob = request.cad_blob;
  mission.cad_name = request.cad_name;
  mission.created_at_ms = clock_();
  write([&](SqlTx& tx) {
    mission.project = project_of_request(tx, request.project);
    if (!find_blob_size(tx, mission.bundle_blob))
      throw NotFound("bundle_blob: blob " + mission.bundle_blob + " not found (upload it first)");
    if (!mission.cad_blob.empty() && !find_blob_size(tx, mission.cad_blob))
      throw NotFound("cad_blob: blob " + mission.cad_blob + " not found (upload it first)");
    tx.exec(
        "INSERT INTO missions (id, name, bundle_blob, cad_blob, cad_name, created_at_ms, "
        "project) VALUES (?1, ?2, ?3, NULLIF(?4, ''), ?5, ?6, ?7)",
        {mission.id, mission.name, mission.bundle_blob, mission.cad_blob, mission.cad_name,
         mission.created_at_ms, mission.project});
    note_blob_ref(tx, mission.project, mission.bundle_blob);
    if (!mission.cad_blob.empty()) note_blob_ref(tx, mission.project, mission.cad_blob);
  });
  return mission;
}

proto::Mission SqlStore::get_mission(const std::string& mission_id) {
  auto mission = read([&](SqlTx& tx) { return find_mission(tx, mission_id); });
  if (!mission) throw NotFound("mission " + mission_id + " not found");
  return *mission;
}

std::vector<proto::Mission> SqlStore::list_missions(const std::string& name_prefix,
                                                    const std::string& project) {
  return read([&](SqlTx& tx) { return query_missions(tx, name_prefix, project); });
}

// --- tokens ---

std::string SqlStore::project_of_request(SqlTx& tx, const std::string& project) {
  if (project.empty()) return proto::kDefaultProject;
  require_project_name(project, "project");
  insert_project(tx, project, clock_());
  return project;
}

proto::TokenInfo SqlStore::add_token(const std::string& token, const TokenSpec& spec) {
  if (token.empty()) throw Invalid("token: expected a non-empty token");
  if (spec.project != proto::kAllProjects)
    require_project_name(spec.project, "project");
  else if (spec.role != proto::Role::kAdmin && spec.role != proto::Role::kWorker)
    throw Invalid("project: '*' (every project) is only for admin and worker tokens");
  const std::string hash = sha256_bytes(token);  // the clear token is never stored
  return write([&](SqlTx& tx) {
    const int64_t now_ms = clock_();
    if (spec.project != proto::kAllProjects) insert_project(tx, spec.project, now_ms);
    tx.exec(
        "INSERT INTO api_tokens (token_sha256, label, created_at_ms, id, role, project, "
        "expires_at_ms) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7) "
        "ON CONFLICT (token_sha256) DO NOTHING",
        {hash, spec.label, now_ms, new_id(kTokenPrefix), proto::to_string(spec.role), spec.project,
         spec.expires_at_ms});
    return read_token(*tx.row(kTokenSelect + " WHERE token_sha256 = ?1", {hash}));
  });
}

std::optional<proto::TokenInfo> SqlStore::check_token(const std::string& token) {
  if (token.empty()) return std::nullopt;
  const std::string hash = sha256_bytes(token);
  auto row =
      read([&](SqlTx& tx) { return tx.row(kTokenSelect + " WHERE token_sha256 = ?1", {hash}); });
  if (!row) return std::nullopt;
  const proto::TokenInfo info = read_token(*row);
  if (info.revoked_at_ms != 0) return std::nullopt;
  if (info.expires_at_ms != 0 && clock_() >= info.expires_at_ms) return std::nullopt;
  return info;
}

std::vector<proto::TokenInfo> SqlStore::list_tokens() {
  return read([&](SqlTx& tx) {
    return read_rows(tx, kTokenSelect + " ORDER BY created_at_ms, {rowid}", {}, read_token);
  });
}

proto::TokenInfo SqlStore::revoke_token(const std::string& token_id) {
  return write([&](SqlTx& tx) {
    tx.exec("UPDATE api_tokens SET revoked_at_ms = ?2 WHERE id = ?1 AND revoked_at_ms = 0",
            {token_id, clock_()});
    auto row = tx.row(kTokenSelect + " WHERE id = ?1", {token_id});
    if (!row) throw NotFound("token " + token_id + " not found");
    return read_token(*row);
  });
}

int64_t SqlStore::token_count() {
  return read([&](SqlTx& tx) { return tx.row("SELECT COUNT(*) FROM api_tokens")->int64(0); });
}

// --- projects ---

std::vector<proto::Project> SqlStore::list_projects() {
  return read([&](SqlTx& tx) {
    return read_rows(tx, kProjectSelect + " ORDER BY name", {}, read_project);
  });
}

proto::Project SqlStore::ensure_project(const std::string& name) {
  require_project_name(name, "project");
  return write([&](SqlTx& tx) {
    insert_project(tx, name, clock_());
    return read_project(*tx.row(kProjectSelect + " WHERE name = ?1", {name}));
  });
}

proto::Project SqlStore::set_project_quota(const std::string& name, int64_t quota_bytes) {
  require_project_name(name, "project");
  if (quota_bytes < 0) throw Invalid("quota_bytes: expected bytes >= 0 (0 = no quota)");
  return write([&](SqlTx& tx) {
    insert_project(tx, name, clock_());
    return read_project(
        *tx.row("UPDATE projects SET quota_bytes = ?2 WHERE name = ?1 "
                "RETURNING name, created_at_ms, quota_bytes",
                {name, quota_bytes}));
  });
}

int64_t SqlStore::project_usage(const std::string& name) {
  return read([&](SqlTx& tx) {
    return tx
        .row(
            "SELECT (SELECT COALESCE(SUM(b.size), 0) FROM blob_refs r "
            "        JOIN blobs b ON b.sha256 = r.sha256 WHERE r.project = ?1) + "
            "       (SELECT COALESCE(SUM(size), 0) FROM uploads WHERE project = ?1)",
            {name})
        ->int64(0);
  });
}

bool SqlStore::project_has_blob(const std::string& name, const std::string& sha256) {
  return read([&](SqlTx& tx) {
    return tx.row("SELECT 1 FROM blob_refs WHERE project = ?1 AND sha256 = ?2", {name, sha256})
        .has_value();
  });
}

// --- metrics ---

Metrics SqlStore::metrics() {
  return read([&](SqlTx& tx) {
    Metrics metrics;
    for (const SqlRow& row : tx.query("SELECT state, COUNT(*) FROM jobs GROUP BY state"))
      metrics.jobs_by_state[static_cast<int>(proto::job_state_from_string(row.text(0)))] =
          row.int64(1);
    const SqlRow counts = *tx.row(
        "SELECT (SELECT COUNT(*) FROM missions), (SELECT COUNT(*) FROM blobs), "
        "(SELECT COALESCE(SUM(size), 0) FROM blobs), (SELECT COUNT(*) FROM uploads)");
    metrics.missions = counts.int64(0);
    metrics.blobs = counts.int64(1);
    metrics.blob_bytes = counts.int64(2);
    metrics.uploads_open = counts.int64(3);
    return metrics;
  });
}

}  // namespace keel::storage
